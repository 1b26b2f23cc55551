// The Python module's fits, diagnoses and calibration: their options from keyword arguments
// and their handles (module.hpp).
#include "module.hpp"

namespace lmcal::python {

namespace {

void set_fit_options(FitOptions& fit, const py::dict& o) {
  if (o.contains("loss"))
    fit.loss = parse_robust_loss(o["loss"].cast<std::string>(), "loss");
  if (o.contains("loss_scale")) fit.loss_scale = o["loss_scale"].cast<double>();
  if (o.contains("starts")) fit.starts = o["starts"].cast<int>();
  if (o.contains("seed")) fit.seed = o["seed"].cast<std::uint64_t>();
  if (o.contains("profile"))
    fit.profile = parse_profile_mode(o["profile"].cast<std::string>(), "profile");
  if (o.contains("covariance"))
    fit.covariance = parse_covariance_method(o["covariance"].cast<std::string>(), "covariance");
  if (o.contains("bootstrap")) fit.bootstrap = o["bootstrap"].cast<std::size_t>();
  if (fit.starts < 0) throw InvalidParameter("starts", fit.starts, "at least 0");
  require_positive("loss_scale", fit.loss_scale);
}

// Every constant's start (given by start= or fixed=, or the paper's) inside its bounds, and
// every bounds given a finite range: InvalidParameter naming the constant, its value and its
// bounds otherwise (the solver would refuse a free one later, and hold a fixed one silently).
void check_starts(const FrictionFitOptions& f, const py::dict& o) {
  const auto given = [&](const char* option, const std::string& name) {
    return o.contains(option) && o[option].cast<py::dict>().contains(name);
  };
  for (std::size_t j = 0; j < kFrictionConstantNames.size(); ++j) {
    const std::string name = kFrictionConstantNames[j];
    const auto [low, high] = f.bounds[j];
    if (given("bounds", name) && !(std::isfinite(low) && std::isfinite(high) && low < high))
      throw InvalidParameter(name, fmt::format("bounds=({}, {}): expected finite low < high", low, high));
    const double value = fittable_constant(f.start, j);
    if (value >= low && value <= high) continue;
    const char* option = given("fixed", name) ? "fixed" : given("start", name) ? "start" : nullptr;
    throw InvalidParameter(name, option ? fmt::format("{} = {} is outside its bounds [{}, {}]: give a value inside them, "
                                                      "or bounds that contain it",
                                                      option, value, low, high)
                                        : fmt::format("the paper's start {} is outside the bounds given [{}, {}]: give a "
                                                      "start inside them (start=)",
                                                      value, low, high));
  }
}

// The options of `lmcal fit friction`, from the keyword arguments of lmcal.fit_friction.
void set_friction_options(FrictionFitOptions& f, const py::dict& o) {
  set_fit_options(f.fit, o);
  if (o.contains("free") && !o["free"].is_none()) {
    f.free.fill(false);
    for (const auto& name : o["free"].cast<std::vector<std::string>>()) f.free[friction_constant_index("free", name)] = true;
  }
  if (o.contains("start"))
    for (const auto& [name, value] : o["start"].cast<std::map<std::string, double>>())
      fittable_constant(f.start, friction_constant_index("start", name)) = value;
  if (o.contains("fixed"))
    for (const auto& [name, value] : o["fixed"].cast<std::map<std::string, double>>()) {
      const std::size_t j = friction_constant_index("fixed", name);
      fittable_constant(f.start, j) = value;
      f.free[j] = false;
    }
  if (o.contains("bounds"))
    for (const auto& [name, range] : o["bounds"].cast<std::map<std::string, std::pair<double, double>>>())
      f.bounds[friction_constant_index("bounds", name)] = range;
  check_starts(f, o);
  if (o.contains("effects")) f.effects = o["effects"].cast<std::vector<std::string>>();
  if (o.contains("run_offsets"))
    f.run_offsets = parse_run_offsets(o["run_offsets"].cast<std::string>(), "run_offsets");
  if (o.contains("law_temperature"))
    f.temperature = parse_friction_temperature(o["law_temperature"].cast<std::string>(), "law_temperature");
  if (o.contains("weights"))
    f.weighting = parse_friction_weighting(o["weights"].cast<std::string>(), "weights");
  if (o.contains("run_fits")) f.per_run_fits = o["run_fits"].cast<bool>();
  if (o.contains("cross_validate")) f.cross_validate = o["cross_validate"].cast<bool>();
}

FrictionFit fit_friction_py(const FrictionData& data, const py::dict& o, const std::string& name,
                            const std::vector<std::string>& command) {
  FrictionFitOptions options;
  set_friction_options(options, o);
  FrictionFit fit{nullptr, data.log, options, {name, data.inputs, command}};
  py::gil_scoped_release release;
  FrictionFitResult result = fit_friction(*data.log, options);
  warn_of_missed_structure(*data.log, options, result);  // as `lmcal fit friction` does
  fit.result = std::make_shared<FrictionFitResult>(std::move(result));
  return fit;
}

// The options of `lmcal fit thermal` (and of a thermal diagnosis' fits).
void set_thermal_options(ThermalFitOptions& t, const py::dict& o, Inputs& inputs) {
  set_fit_options(t.fit, o);
  if (o.contains("heat"))
    t.heat = parse_heat_input(o["heat"].cast<std::string>(), "heat");
  if (o.contains("source")) t.source = parse_source_model(o["source"].cast<std::string>());
  if (o.contains("scheme")) t.scheme = parse_time_scheme(o["scheme"].cast<std::string>());
  if (o.contains("half_rail_segments")) t.half_rail_segments = o["half_rail_segments"].cast<int>();
  if (o.contains("time_step_s")) t.time_step_s = o["time_step_s"].cast<double>();
  if (o.contains("every")) t.every = o["every"].cast<std::size_t>();
  if (o.contains("ambient")) t.ambient = o["ambient"].cast<std::string>();
  if (o.contains("alpha_start")) t.alpha_start = o["alpha_start"].cast<double>();
  if (o.contains("fit_h")) t.fit_h = o["fit_h"].cast<bool>();
  if (o.contains("h_W_m2K")) t.h_W_m2K = o["h_W_m2K"].cast<double>();
  if (o.contains("offsets"))
    t.offsets = parse_thermal_offsets(o["offsets"].cast<std::string>(), "offsets");
  if (o.contains("fit_initial")) t.fit_initial_temperature = o["fit_initial"].cast<bool>();
  if (o.contains("extensions")) t.extensions = o["extensions"].cast<std::vector<std::string>>();
  if (o.contains("run_fits")) t.per_run_fits = o["run_fits"].cast<bool>();
  if (o.contains("cross_validate")) t.cross_validate = o["cross_validate"].cast<bool>();
  if (!o.contains("friction") || o["friction"].is_none()) return;
  const py::object friction = o["friction"];
  if (py::isinstance<FrictionFit>(friction)) {  // a fit of this session: its constants, effects and covariance
    const FrictionFit& f = friction.cast<const FrictionFit&>();
    t.friction = f.result->constants();
    t.friction_effects = f.result->effects();
    t.friction_fit = f.result->fit;
    inputs.insert(inputs.begin(), f.provenance.inputs.begin(), f.provenance.inputs.end());
  } else {  // a friction fit JSON, as `lmcal fit thermal --friction FILE` reads it
    const auto file = py::str(friction).cast<std::string>();
    read_friction_fit(file, t);
    inputs.insert(inputs.begin(), {file, sha256_file(file)});
  }
}

ThermalFit fit_thermal_py(const ThermalData& data, const py::dict& o, const std::string& name,
                          const std::vector<std::string>& command) {
  ThermalFit fit{nullptr, data.set, {}, data.inputs, command, name};
  set_thermal_options(fit.options, o, fit.inputs);
  py::gil_scoped_release release;
  fit.result = std::make_shared<ThermalFitResult>(fit_thermal(*data.set, fit.options));
  return fit;
}

FrictionDiagnosisHandle diagnose_friction_py(const FrictionData& data, const py::dict& o, const py::object& progress) {
  FrictionDiagnosisOptions options;
  set_friction_options(options.fit, o);
  if (o.contains("lrt_p")) options.lrt_p = o["lrt_p"].cast<double>();
  if (o.contains("min_gain_percent")) options.min_cv_gain_percent = o["min_gain_percent"].cast<double>();
  options.progress = python_progress(progress);
  py::gil_scoped_release release;
  return {std::make_shared<FrictionDiagnosis>(diagnose_friction(*data.log, options))};
}

ThermalDiagnosisHandle diagnose_thermal_py(const ThermalData& data, const py::dict& o, const py::object& progress) {
  ThermalDiagnosisOptions options;
  Inputs unused;
  set_thermal_options(options.fit, o, unused);
  if (o.contains("lrt_p")) options.lrt_p = o["lrt_p"].cast<double>();
  if (o.contains("min_gain_percent")) options.min_cv_gain_percent = o["min_gain_percent"].cast<double>();
  options.progress = python_progress(progress);
  py::gil_scoped_release release;
  return {std::make_shared<ThermalDiagnosis>(diagnose_thermal(*data.set, options))};
}

CalibrationHandle calibrate_py(const std::string& folder, const py::dict& o, const py::object& progress) {
  const CalibrationSet set = find_calibration_set(folder);
  CalibrationOptions options;
  if (o.contains("catalog") && !o["catalog"].is_none()) options.catalog_file = o["catalog"].cast<std::string>();
  if (o.contains("raw")) options.raw = raw_options(o["raw"].cast<py::dict>(), &options.raw_given);
  if (o.contains("diagnose")) options.diagnose = o["diagnose"].cast<bool>();
  if (o.contains("allow_outside_root")) options.inputs.allow_outside = o["allow_outside_root"].cast<bool>();
  // One setting, every step that has it (as `lmcal calibrate` applies its options).
  py::dict friction = o.contains("friction") ? o["friction"].cast<py::dict>() : py::dict();
  set_friction_options(options.friction, friction);
  set_friction_options(options.friction_diagnosis.fit, friction);
  for (FitOptions* fit : {&options.friction.fit, &options.friction_diagnosis.fit.fit, &options.thermal.fit,
                          &options.thermal_diagnosis.fit.fit})
    set_fit_options(*fit, o["uncertainty"].cast<py::dict>());
  const Progress detail = python_progress(progress);
  CalibrationProgress callbacks{.step = [detail](std::size_t step, std::size_t steps, const std::string& name) {
                                  detail(name, step, steps);
                                },
                                .detail = detail};
  py::gil_scoped_release release;
  return {std::make_shared<Calibration>(calibrate(set, options, callbacks))};
}

}  // namespace

void bind_fits(py::module_& m) {
  py::class_<FrictionFit>(m, "FrictionFitHandle")
      .def("json", &FrictionFit::json)
      .def("summary", [](const FrictionFit& f) { return friction_fit_summary(*f.result); })
      .def("write", [](const FrictionFit& f, const std::string& dir) { write_files(dir, f.files()); })
      .def("arrays", &FrictionFit::arrays)
      .def("constants", [](const FrictionFit& f) {
        const auto k = f.result->constants();
        std::map<std::string, double> out;
        for (std::size_t j = 0; j < kFrictionConstantNames.size(); ++j) out[kFrictionConstantNames[j]] = fittable_constant(k, j);
        return out;
      })
      .def("effects", [](const FrictionFit& f) {
        std::map<std::string, double> out;
        for (const auto& name : f.options.effects) out[name] = f.result->fit.parameter(name).value;
        return out;
      })
      .def("log", [](const FrictionFit& f) { return FrictionData{f.log, f.provenance.inputs}; })
      .def("eval", [](const FrictionFit& f, const py::dict& columns) { return friction_law_at(f.law(), columns); })
      .def("unlogged_conditions", &FrictionFit::unlogged_conditions);
  m.def("fit_friction", &fit_friction_py);

  py::class_<ThermalFit>(m, "ThermalFitHandle")
      .def("json", &ThermalFit::json)
      .def("summary", [](const ThermalFit& f) { return thermal_fit_summary(*f.result); })
      .def("write", [](const ThermalFit& f, const std::string& dir) { write_files(dir, f.files()); })
      .def("arrays", &ThermalFit::arrays);
  m.def("fit_thermal", &fit_thermal_py);

  py::class_<FrictionDiagnosisHandle>(m, "FrictionDiagnosisHandle")
      .def("json", &FrictionDiagnosisHandle::json)
      .def("summary", [](const FrictionDiagnosisHandle& d) { return d.result->summary; });
  py::class_<ThermalDiagnosisHandle>(m, "ThermalDiagnosisHandle")
      .def("json", &ThermalDiagnosisHandle::json)
      .def("summary", [](const ThermalDiagnosisHandle& d) { return d.result->summary; });
  m.def("diagnose_friction", &diagnose_friction_py);
  m.def("diagnose_thermal", &diagnose_thermal_py);

  py::class_<CalibrationHandle>(m, "CalibrationHandle")
      .def("json", &CalibrationHandle::json)
      .def("summary", [](const CalibrationHandle& h) { return calibration_summary(*h.c); })
      .def("write", [](const CalibrationHandle& h, const std::string& dir) { write_files(dir, h.files(), calibration_output_names()); })
      .def("report_html", [](const CalibrationHandle& h) { return calibration_report_html(*h.c); })
      .def("friction", &CalibrationHandle::friction)
      .def("thermal", &CalibrationHandle::thermal)
      .def("friction_diagnosis",
           [](const CalibrationHandle& h) -> std::optional<FrictionDiagnosisHandle> {
             if (!h.c->friction_diagnosis) return std::nullopt;
             return FrictionDiagnosisHandle{{h.c, &*h.c->friction_diagnosis}};
           })
      .def("thermal_diagnosis", [](const CalibrationHandle& h) -> std::optional<ThermalDiagnosisHandle> {
        if (!h.c->thermal_diagnosis) return std::nullopt;
        return ThermalDiagnosisHandle{{h.c, &*h.c->thermal_diagnosis}};
      });
  m.def("calibrate", &calibrate_py);
}

}  // namespace lmcal::python
