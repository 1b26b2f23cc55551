// The Python module's models at work: the friction law at given conditions, a case of the
// rail's simulation, the virtual rig's friction log and a duty cycle's prediction (module.hpp).
#include "module.hpp"

namespace lmcal::python {

py::array_t<double> friction_law_at(const FrictionLaw& law, const py::dict& columns) {
  using Column = py::array_t<double, py::array::c_style | py::array::forcecast>;
  const auto column = [&](const char* name) { return columns[name].cast<Column>(); };
  const auto optional = [&](const char* name) { return columns.contains(name) ? std::optional(column(name)) : std::nullopt; };
  const Column v = column("velocity_m_s"), load = column("load_N"), preload = column("preload_um"),
               block = column("block_length_mm"), temperature = column("temperature_C"),
               viscosity = column("viscosity40_mm2_s"), direction = column("direction");
  const auto acceleration = optional("acceleration_m_s2"), position = optional("position_m"),
             travel = optional("distance_since_reversal_m");
  const auto n = v.size();
  py::array_t<double> out(n);
  auto f = out.mutable_unchecked<1>();
  for (py::ssize_t i = 0; i < n; ++i) {
    const auto row = static_cast<std::size_t>(i);
    const FrictionConditions<double> c{.load_N = load.at(i), .preload_um = preload.at(i), .block_length_mm = block.at(i),
                                       .velocity_m_s = v.at(i), .temperature_C = temperature.at(i), .direction = direction.at(i),
                                       .acceleration_m_s2 = acceleration ? acceleration->at(i) : 0.0,
                                       .position_m = position ? position->at(i) : 0.0,
                                       .distance_since_reversal_m = travel ? travel->at(i) : 0.0};
    FrictionConstants<double> k = law.constants;
    k.nu_ref_mm2_s = viscosity.at(i);
    try {
      validate(c);
      require_positive("viscosity40_mm2_s", k.nu_ref_mm2_s);
      if (c.direction != 1 && c.direction != -1) throw InvalidParameter("direction", c.direction, "+1 or -1");
    } catch (const InvalidParameter& e) {
      throw ConditionError(e.parameter(), row, e.what());
    }
    f(i) = friction_force_with_effects_N(k, law.effects, c) + (law.terms.empty() ? 0.0 : steady_terms_N(law.terms, k, law.effects, c));
    // The last check before the array leaves: the constants given may still take the law out of the doubles.
    if (!std::isfinite(f(i)))
      throw ConditionError("velocity_m_s", row,
                           fmt::format("the friction law gives {} N at velocity_m_s = {}: expected a condition where it is finite",
                                       f(i), v.at(i)));
  }
  return out;
}

namespace {

FrictionConstants<double> constants_from(const std::map<std::string, double>& given) {
  FrictionConstants<double> k = paper_friction_constants();
  for (const auto& [name, value] : given) fittable_constant(k, friction_constant_index("constants", name)) = value;
  validate(k);
  return k;
}

FrictionEffects<double> effects_from(const std::map<std::string, double>& given) {
  FrictionEffects<double> e;
  for (const auto& [name, value] : given) e[friction_effect_slot(name)] = value;
  return e;
}

// One case of `lmcal simulate thermal`: the rail of a catalog guide heated by one block.
py::dict simulate_thermal_py(const py::dict& o) {
  const GuideSpec spec = find_guide(o["guide"].cast<std::string>());
  const auto number = [&](const char* name) { return o[name].cast<double>(); };
  const auto given_or_catalog = [&](const char* name, std::optional<double> GuideSpec::*field) {
    return o[name].is_none() ? require(spec, field, name) : number(name);
  };
  const AmbientTrace ambient = py::isinstance<py::float_>(o["ambient_C"]) || py::isinstance<py::int_>(o["ambient_C"])
                                   ? AmbientTrace::constant(number("ambient_C"))
                                   : [&] {
                                       const auto [t, T] = o["ambient_C"].cast<std::pair<std::vector<double>, std::vector<double>>>();
                                       return AmbientTrace{t, T};
                                     }();
  const double initial_C = o["initial_C"].is_none() ? ambient.temperature_C.front() : number("initial_C");
  RailParams<double> params = rail_material_of(spec);
  params.heat_partition = number("alpha");
  params.h_W_m2K = number("h_W_m2K");
  params.initial_temperature_C = initial_C;
  const double V = number("velocity_m_s");
  require_in_range("velocity_m_s", V, 0.0, physical_range(Quantity::velocity).high);
  if (o["heat_rate_W"].is_none()) {
    FrictionConditions<double> c{.load_N = number("load_N"),
                                 .preload_um = given_or_catalog("preload_um", &GuideSpec::preload_um),
                                 .block_length_mm = given_or_catalog("block_length_mm", &GuideSpec::block_length_mm),
                                 .velocity_m_s = V,
                                 .temperature_C = initial_C};
    validate(c);
    params.heat_rate_W = heat_rate_with_effects_W(constants_from(o["constants"].cast<std::map<std::string, double>>()),
                                                  effects_from(o["effects"].cast<std::map<std::string, double>>()), c);
  } else {
    params.heat_rate_W = number("heat_rate_W");
  }
  const RailGeometry geometry = rail_geometry_of(spec, number("rail_length_m"), number("stroke_m"),
                                                given_or_catalog("contact_length_mm", &GuideSpec::contact_length_mm) * 1e-3, V);
  const RailNumerics numerics{.source = parse_source_model(o["source"].cast<std::string>()),
                              .scheme = parse_time_scheme(o["scheme"].cast<std::string>()),
                              .half_rail_segments = o["segments"].cast<int>(),
                              .time_step_s = number("time_step_s")};
  const double duration = number("duration_s"), every = number("output_every_s");
  require_positive("duration_s", duration);
  require_positive("output_every_s", every);
  RailOutputs outputs{.duration_s = duration, .sensor_positions_m = o["sensors_m"].cast<std::vector<double>>()};
  for (double t = 0; t < duration; t += every) outputs.output_times_s.push_back(t);
  outputs.output_times_s.push_back(duration);
  outputs.profile_times_s = {duration};
  RailSolution<double> s;
  {
    py::gil_scoped_release release;
    s = simulate_rail(geometry, numerics, outputs, params, ambient);
  }
  // The last check before the arrays leave.
  if (const std::string runaway = runaway_of(s, fmt::format("velocity_m_s = {}, heat_rate_W = {}", V, params.heat_rate_W));
      !runaway.empty())
    throw InvalidParameter("simulate_thermal", runaway);
  py::dict d;
  d["time_s"] = array(s.output_times_s);
  d["sensor_x_m"] = array(s.sensor_positions_m);
  py::array_t<double> temperature({s.output_times_s.size(), s.sensor_positions_m.size()});
  std::copy(s.sensor_temperature_C.begin(), s.sensor_temperature_C.end(), temperature.mutable_data());
  d["temperature_C"] = temperature;
  d["heat_rate_W"] = params.heat_rate_W;
  d["x_m"] = array(s.node_positions_m);
  d["profile_C"] = array(s.profiles_C.front());
  d["time_step_s"] = s.time_step_s;
  return d;
}

// `lmcal generate friction` (the virtual rig) in memory: its options by the names of
// FrictionRigConfig (lmcal.generate_friction checks their types), effects by rig effect name.
FrictionRigOutput generate_friction_py(const py::dict& o) {
  FrictionRigConfig config;
  for (const auto& [key, value] : o) {
    const auto name = key.cast<std::string>();
    const auto list = [&] { return value.cast<std::vector<double>>(); };
    if (name == "guides") config.guides = value.cast<std::vector<std::string>>();
    else if (name == "preload_um") config.preload_um = list();
    else if (name == "load_N") config.load_N = list();
    else if (name == "velocity_m_s") config.velocity_m_s = list();
    else if (name == "temperature_C") config.temperature_C = list();
    else if (name == "runs") config.runs = value.cast<int>();
    else if (name == "one_setup_per_run") config.one_setup_per_run = value.cast<bool>();
    else if (name == "temperature_outermost") config.temperature_outermost = value.cast<bool>();
    else if (name == "shuffle_runs") config.shuffle_runs = value.cast<bool>();
    else if (name == "noise_N") config.noise_N = value.cast<double>();
    else if (name == "noise_ar1") config.noise_ar1 = value.cast<double>();
    else if (name == "run_offset_N") config.run_offset_N = value.cast<double>();
    else if (name == "temperature_noise_K") config.temperature_noise_K = value.cast<double>();
    else if (name == "seed") config.seed = value.cast<std::uint64_t>();
    else if (name == "constants") config.constants = constants_from(value.cast<std::map<std::string, double>>());
    else if (name != "effects") throw InvalidParameter(name, "not an option of the virtual rig");
  }
  require_autocorrelation("noise_ar1", config.noise_ar1);
  RigEffects effects;
  if (o.contains("effects"))
    for (const auto& [name, value] : o["effects"].cast<std::map<std::string, double>>()) set_rig_effect(effects, name, value);
  py::gil_scoped_release release;
  return generate_friction_log(config, effects);
}

// `lmcal predict MODEL DUTY`: prediction.json's text, the summary, and the bands as arrays.
py::dict predict_py(const std::string& model_file, const std::string& duty_file, std::size_t samples, std::uint64_t seed,
                    const std::vector<std::string>& command, bool allow_outside_root) {
  std::string json, summary;
  Prediction p;
  {
    py::gil_scoped_release release;
    const ModelFile model = read_model_file(model_file);
    const DutyCycle duty = load_duty_cycle(duty_file, nullptr, {.allow_outside = allow_outside_root});
    p = predict(model, duty, {.samples = samples, .seed = seed});
    json = prediction_json(p, duty, model, command);
    summary = prediction_summary(p);
  }
  const auto band = [](const Band& b) {
    py::dict d;
    d["value"] = array(b.value);
    d["low"] = array(b.low);
    d["high"] = array(b.high);
    return d;
  };
  py::dict d;
  d["json"] = json;
  d["summary"] = summary;
  d["time_s"] = array(p.time_s);
  d["segment"] = p.segment;
  d["elongation_um"] = band(p.elongation_um);
  py::list temperatures, scale;
  for (const auto& b : p.temperature_C) temperatures.append(band(b));
  for (const auto& b : p.scale_error_um) scale.append(band(b));
  d["temperature_C"] = temperatures;
  d["scale_error_um"] = scale;
  d["positions_m"] = array(p.positions_m);
  d["scale_positions_m"] = array(p.scale_positions_m);
  d["friction_N"] = band(p.friction_N);
  d["heat_rate_W"] = band(p.heat_rate_W);
  return d;
}

}  // namespace

void bind_simulation(py::module_& m) {
  m.def("predict", &predict_py);
  m.def("friction_law", [](const std::map<std::string, double>& constants, const std::map<std::string, double>& effects,
                           const py::dict& columns) {
    return friction_law_at({constants_from(constants), effects_from(effects), {}}, columns);
  });
  m.def("simulate_thermal", &simulate_thermal_py);
  m.def("generate_friction", [](const py::dict& o) {
    const FrictionRigOutput made = generate_friction_py(o);
    return std::pair(FrictionData{std::make_shared<FrictionLog>(made.log), {}}, made.truth_json);
  });
  m.def("guide", [](const std::string& model, const std::optional<std::string>& catalog) {
    const auto user = user_catalog(catalog);
    const GuideSpec& spec = find_guide(model, user ? &*user : nullptr);
    py::dict d;
    d["model"] = spec.model;
    d["kind"] = spec.kind;
    d["source"] = spec.source;
    for (const auto& field : guide_field_names())
      if (const auto value = field_value(spec, field)) d[py::str(field)] = *value;
    return d;
  });
  m.def("friction_effect_names", &friction_effect_names);
}

}  // namespace lmcal::python
