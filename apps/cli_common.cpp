#include "cli_common.hpp"

#include "lmcal/io/output_record.hpp"
#include "output_mode.hpp"

#include "lmcal/io/hash.hpp"
#include "lmcal/io/limits.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <charconv>
#include <iostream>
#include <cmath>

#include "lmcal/error.hpp"
#include "lmcal/io/atomic_file.hpp"
#include "lmcal/io/printable.hpp"

namespace lmcal::cli {

namespace {

double parse_number(std::string_view option, std::string_view token, std::string_view expected) {
  while (!token.empty() && token.front() == ' ') token.remove_prefix(1);
  while (!token.empty() && token.back() == ' ') token.remove_suffix(1);
  double value = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (token.empty() || ec != std::errc() || end != token.data() + token.size() || !std::isfinite(value))
    throw InvalidParameter(std::string(option), fmt::format("'{}' is not a number; expected {}", token, expected));
  return value;
}

std::vector<std::string_view> split(std::string_view text, char separator) {
  std::vector<std::string_view> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t at = text.find(separator, start);
    parts.push_back(text.substr(start, at == std::string_view::npos ? std::string_view::npos : at - start));
    if (at == std::string_view::npos) return parts;
    start = at + 1;
  }
}

}  // namespace

void add_keep_unusable(CLI::App& app, bool& keep) {
  app.add_flag("--keep-unusable", keep,
               "Write the outputs of a fit that gives no usable answer (non-finite residuals, no degree of freedom "
               "left, a failed solver) and exit 0; without it such a run writes nothing and exits with status 4");
}

void require_usable(const std::optional<std::string>& why, bool keep) {
  if (!why) return;
  if (!keep) throw UnusableFit(*why + "; nothing was written (--keep-unusable writes the outputs anyway)");
  std::cerr << "lmcal: warning: " << *why << " (kept: --keep-unusable)\n";
}

std::string plural(std::size_t n, std::string_view noun) { return fmt::format("{} {}{}", n, noun, n == 1 ? "" : "s"); }

InputScope& input_scope() {
  static InputScope scope;
  return scope;
}

std::string filesystem_message(const std::filesystem::filesystem_error& e) {
  std::string paths;
  for (const auto* p : {&e.path1(), &e.path2()})
    if (!p->empty()) paths += (paths.empty() ? "" : " -> ") + io::printable(p->string());
  return fmt::format("{}: {}", paths.empty() ? std::string("file system") : paths, e.code().message());
}

void require_writable_output(const std::filesystem::path& folder) {
  if (auto problem = output_folder_problem(folder)) throw InvalidParameter("-o", *problem);
}

std::string write_outputs(const std::filesystem::path& dir, std::vector<std::pair<std::string, std::string>> files,
                          const std::vector<std::string>& replaced) {
  OutputSet out;
  for (const std::string& name : replaced) out.remove(dir / name);
  std::string written;
  for (std::size_t i = 0; i < files.size(); ++i) {
    const std::filesystem::path path = dir / files[i].first;
    if (path.extension() == ".json") {
      files[i].second = with_output_record(files[i].second);
      offer_machine_output(path, path.filename() == "calibration.json" || path.filename() == "fleet.json");
    }
    written += (i == 0 ? "" : i + 1 == files.size() ? " and " : ", ") + path.string();
    out.add(path, std::move(files[i].second));
  }
  out.commit();
  return written;
}

std::vector<double> parse_list(std::string_view option, std::string_view text) {
  constexpr std::string_view kExpected = "a list like 0.066,0.083,0.11 or a range start:stop:step";
  std::vector<double> values;
  for (std::string_view item : split(text, ',')) {
    const auto range = split(item, ':');
    if (range.size() == 1) {
      values.push_back(parse_number(option, item, kExpected));
    } else if (range.size() == 3) {
      const double start = parse_number(option, range[0], kExpected);
      const double stop = parse_number(option, range[1], kExpected);
      const double step = parse_number(option, range[2], kExpected);
      if (!(step > 0) || stop < start)
        throw InvalidParameter(std::string(option), fmt::format("range '{}' needs start <= stop and step > 0", item));
      const auto count = static_cast<long>(std::floor((stop - start) / step + 1e-9));
      if (count > 100000) throw InvalidParameter(std::string(option), fmt::format("range '{}' has over 100000 values", item));
      for (long i = 0; i <= count; ++i) values.push_back(start + static_cast<double>(i) * step);
    } else {
      throw InvalidParameter(std::string(option), fmt::format("'{}' is not understood; expected {}", item, kExpected));
    }
  }
  return values;
}

std::vector<std::pair<double, double>> parse_pairs(std::string_view option, std::string_view text) {
  constexpr std::string_view kExpected = "time_s:temperature_C pairs like 0:26,3600:27.5";
  std::vector<std::pair<double, double>> pairs;
  for (std::string_view item : split(text, ',')) {
    const auto pair = split(item, ':');
    if (pair.size() != 2)
      throw InvalidParameter(std::string(option), fmt::format("'{}' is not understood; expected {}", item, kExpected));
    pairs.emplace_back(parse_number(option, pair[0], kExpected), parse_number(option, pair[1], kExpected));
  }
  return pairs;
}

nlohmann::json run_record(const std::vector<std::string>& argv) {
  return {{"lmcal_version", LMCAL_VERSION}, {"command", argv}};
}

}  // namespace lmcal::cli

namespace lmcal::cli {

void GuideOptions::add_to(CLI::App& app) {
  app.add_option("--guide", guides, "Guide model(s) from the catalog, e.g. \"SRN 35C\" (a list sweeps them)")
      ->delimiter(',')
      ->capture_default_str();
  app.add_option("--catalog", catalog_file, kCatalogHelp);
  add_assignments(app, "--set", overrides, "Override a catalog value: --set conductivity_W_mK=36 (repeatable)");
}

GuideSpec GuideOptions::resolve(const std::string& model) const {
  const std::optional<GuideCatalog> user = catalog_file.empty() ? std::nullopt : std::optional(load_catalog(catalog_file));
  return with_overrides(find_guide(model, user ? &*user : nullptr), overrides);
}

nlohmann::json GuideOptions::record() const {
  nlohmann::json guides_json = nlohmann::json::array();
  for (const auto& model : guides) {
    const GuideSpec spec = resolve(model);
    nlohmann::json g{{"model", spec.model}};
    for (const auto& name : guide_field_names()) {
      const auto value = field_value(spec, name);
      g[name] = value ? nlohmann::json(*value) : nlohmann::json(nullptr);
    }
    g["notes"] = spec.notes;
    guides_json.push_back(std::move(g));
  }
  return {{"catalog", catalog_file.empty() ? "<built-in>" : catalog_file}, {"guides", guides_json}};
}

void FrictionOptions::add_to(CLI::App& app) {
  auto* group = app.add_option_group("Friction constants", "Eq. 8 constants (default: the paper's)");
  options_ = {
      group->add_option("--k1", constants.k1, "Coulomb coefficient k1")->capture_default_str(),
      group->add_option("--k2", constants.k2, "Preload reduction k2, 1/um")->capture_default_str(),
      group->add_option("--mu-st", constants.mu_st, "Stribeck coefficient muSt")->capture_default_str(),
      group->add_option("--v-st", constants.v_st_m_s, "Stribeck velocity VSt, m/s")->capture_default_str(),
      group->add_option("--mu-v", constants.mu_v, "Viscous coefficient muv")->capture_default_str(),
      group->add_option("--beta", constants.beta_per_K, "Viscosity-temperature coefficient beta, 1/K")->capture_default_str(),
      group->add_option("--f0", constants.f0, "Viscous offset f0, N/mm")->capture_default_str(),
      group->add_option("--viscosity40", constants.nu_ref_mm2_s, "Oil viscosity at the reference temperature, mm2/s")
          ->capture_default_str(),
      group->add_option("--reference-temperature", constants.T_ref_C, "Reference temperature of the viscosity, C")
          ->capture_default_str()};
}

FrictionLaw FrictionOptions::law(const LoadedModel* model) const {
  if (!model || !model->model.has_friction) return {.constants = constants};
  model->refuse(given(options_), "the friction law's constants (and its viscosity at the reference temperature)");
  model->model.require_friction_scalings("a simulation");
  return {.constants = model->model.constants,
          .effects = model->model.effects,
          .effect_names = model->model.friction_causes,
          .terms = model->model.friction_terms};
}

void FrictionLaw::record_into(nlohmann::json& record) const {
  const auto& k = constants;
  record["friction_constants"] = {{"k1", k.k1},       {"k2", k.k2},         {"mu_st", k.mu_st},
                                  {"v_st_m_s", k.v_st_m_s}, {"mu_v", k.mu_v}, {"beta_per_K", k.beta_per_K},
                                  {"f0", k.f0},       {"nu_ref_mm2_s", k.nu_ref_mm2_s}, {"T_ref_C", k.T_ref_C}};
  nlohmann::json e = nlohmann::json::object();
  for (const auto& name : effect_names) e[name] = effects[friction_effect_slot(name)];
  record["friction_effects"] = e;
}

std::string FrictionLaw::effects_text() const {
  return effect_names.empty() ? "none" : fmt::format("{}", fmt::join(effect_names, ", "));
}

std::vector<std::string> given(const std::vector<const CLI::Option*>& options) {
  std::vector<std::string> names;
  for (const CLI::Option* o : options)
    if (o->count() > 0) names.push_back(o->get_name());
  return names;
}

void FrictionInputOptions::add_to(CLI::App& app) {
  auto* group = app.add_option_group("Raw load-cell logs", "How a raw log (force_N, time_s, position or velocity) is cut into plateaus");
  const auto add = [&](CLI::Option* option, const char* field) {
    option->capture_default_str();
    options_.emplace_back(option, field);
  };
  add(completes(group->add_option("--force-sign", force_sign, "follows-motion (positive moving towards +x), opposes-motion or magnitude"),
                {"follows-motion", "opposes-motion", "magnitude"}),
      "force_sign");
  add(group->add_option("--max-acceleration", raw.max_acceleration_m_s2, "|a| above which a sample is a transient, m/s2"),
      "max_acceleration_m_s2");
  add(group->add_option("--settling", raw.settling_s, "Dropped after every acceleration, s"), "settling_s");
  add(group->add_option("--min-speed", raw.min_speed_m_s, "Slower is at rest, m/s"), "min_speed_m_s");
  add(group->add_option("--speed-tolerance", raw.velocity_tolerance,
                        "A sample off its plateau's median speed by more than this share is a transient"),
      "velocity_tolerance");
  add(group->add_option("--min-plateau", raw.min_plateau_samples, "Fewest samples of a kept plateau"), "min_plateau_samples");
  add(group->add_option("--velocity-window", raw.velocity_window, "Samples of the filter deriving v and a (odd)"),
      "velocity_window");
  add(group->add_option("--moving-mass", raw.moving_mass_kg, "Moving mass, kg: the inertia m*a is taken off the force"),
      "moving_mass_kg");
  add(group->add_option("--duplicate-times", duplicate_times, "Samples sharing a time: average (merged) or refuse"),
      "duplicate_times");
  add(group->add_option("--skip-lines", raw.skip_lines, kSkipLinesHelp),
      "skip_lines");
  add_drive_options(app);
  add(completes(group->add_option("--segmentation", segmentation,
                        "plateaus (a rig's constant-speed plateaus) or trajectory (a drive's log kept whole; the moving "
                        "mass is fitted with the law)"),
                {"plateaus", "trajectory"}),
      "segmentation");
  add(group->add_option("--trajectory-window", raw.trajectory_window,
                        "Samples of a trajectory's velocity filter (odd; 0: chosen from the data)"),
      "trajectory_window");
  add(group->add_option("--presliding", raw.presliding_m,
                        "A trajectory's travel after rest or a reversal dropped as pre-sliding, m"),
      "presliding_m");
  add(group->add_option("--axis-incline", raw.axis_incline_deg,
                        "The axis's incline, degrees (90: vertical, +x up; 0 states a horizontal axis); a trajectory "
                        "then fits the weight"),
      "axis_incline_deg");
  add(completes(group->add_option("--force-sensor", force_sensor,
                        "What measured the force: load_cell, motor_current, torque_sensor or unknown (what a "
                        "diagnosis may name: a load cell's zero needs a load cell)"),
                {"load_cell", "motor_current", "torque_sensor", "unknown"}),
      "force_sensor");
  app.add_option("--catalog", catalog_file, kCatalogHelp);
}

namespace {
std::map<const CLI::Option*, std::vector<std::string>>& value_registry() {
  static std::map<const CLI::Option*, std::vector<std::string>> values;
  return values;
}
}  // namespace

CLI::Option* completes(CLI::Option* option, std::vector<std::string> values) {
  value_registry()[option] = std::move(values);
  return option;
}

const std::vector<std::string>* completion_values(const CLI::Option* option) {
  const auto it = value_registry().find(option);
  return it == value_registry().end() ? nullptr : &it->second;
}

namespace {
std::map<const CLI::Option*, std::vector<std::string>>& alias_registry() {
  static std::map<const CLI::Option*, std::vector<std::string>> aliases;
  return aliases;
}
}  // namespace

CLI::Option* hidden_alias(CLI::Option* option, const std::string& name) {
  alias_registry()[option].push_back(name);
  return option;
}

std::vector<std::string> shown_long_names(const CLI::Option* option) {
  std::vector<std::string> names = option->get_lnames();
  if (const auto it = alias_registry().find(option); it != alias_registry().end())
    std::erase_if(names, [&](const std::string& n) { return std::find(it->second.begin(), it->second.end(), n) != it->second.end(); });
  return names;
}

std::string HelpFormatter::make_option_name(const CLI::Option* option, bool is_positional) const {
  if (is_positional || !alias_registry().contains(option)) return CLI::Formatter::make_option_name(option, is_positional);
  std::vector<std::string> names;
  for (const auto& n : option->get_snames()) names.push_back("-" + n);
  for (const auto& n : shown_long_names(option)) names.push_back("--" + n);
  return fmt::format("{}", fmt::join(names, ","));
}

void FrictionInputOptions::add_drive_options(CLI::App& app) {
  auto* group = app.add_option_group("Rotary drive", "How a log's motor speed (velocity_rpm, velocity_rad_s) and torque "
                                                     "(torque_Nm, torque_percent) become the carriage's (docs/formats.md)");
  Drive& d = raw.drive;
  const auto add = [&](CLI::Option* option, const char* field) { options_.emplace_back(option, field); };
  add(group->add_option("--lead", d.lead_mm, "Screw lead, mm (travel per screw turn)"), "lead_mm");
  add(group->add_option("--pinion-radius", d.pinion_radius_mm, "Rack and pinion: the pinion's pitch radius, mm"),
      "pinion_radius_mm");
  add(group->add_option("--gear-ratio", d.gear_ratio, "Motor turns per screw or pinion turn (default 1)"), "gear_ratio");
  add(group->add_option("--efficiency", d.efficiency, "The drive's efficiency, 0 < eta <= 1 (default 1)"), "efficiency");
  add(group->add_option("--rotor-inertia", d.rotor_inertia_kg_m2, "Motor and gearbox inertia at the motor, kg m2"),
      "rotor_inertia_kg_m2");
  add(group->add_option("--nominal-torque", d.nominal_torque_Nm, "The motor's nominal torque, N m (for torque_percent)"),
      "nominal_torque_Nm");
}

std::vector<std::string> FrictionInputOptions::raw_given() const {
  std::vector<std::string> names;
  for (const auto& [option, field] : options_)
    if (option->count() > 0) names.push_back(field);
  return names;
}

RawFrictionOptions FrictionInputOptions::parsed() const {
  RawFrictionOptions r = raw;
  r.force_sign = parse_force_sign(force_sign);
  r.duplicate_times = parse_duplicate_times(duplicate_times);
  r.segmentation = parse_raw_segmentation(segmentation);
  r.force_sensor = parse_force_sensor(force_sensor);
  for (const auto& [option, field] : options_)
    if (option->count() > 0 && field == std::string_view("axis_incline_deg")) r.incline_stated = true;
  return r;
}

std::optional<GuideCatalog> user_catalog(const std::string& file) {
  return file.empty() ? std::nullopt : std::optional(load_catalog(file));
}

FrictionInput read_friction_input(const std::vector<std::string>& files, const FrictionInputOptions& options) {
  FrictionInput in;
  const auto is_manifest = [](const std::string& f) { return std::filesystem::path(f).extension() == ".toml"; };
  const auto manifests = std::count_if(files.begin(), files.end(), is_manifest);
  const std::optional<GuideCatalog> catalog = user_catalog(options.catalog_file);
  if (catalog) in.inputs.emplace_back(options.catalog_file, "");
  if (manifests == 0) {
    in.raw = options.parsed();
    in.log = load_friction_logs(std::vector<std::filesystem::path>(files.begin(), files.end()), in.raw);
    for (const auto& file : files) in.inputs.emplace_back(file, "");
    return in;
  }
  if (files.size() != 1)
    throw InvalidParameter("files", "give one friction manifest (.toml), or CSV logs, not both or several manifests");
  FrictionDataSet set = load_friction_dataset(files.front(), catalog ? &*catalog : nullptr, options.parsed(),
                                              options.raw_given(), input_scope());
  in.inputs.emplace_back(files.front(), "");
  for (const auto& file : set.files) in.inputs.emplace_back(file.string(), "");
  in.raw = set.raw;
  in.log = std::move(set.log);
  return in;
}

FrictionInput load_friction_input(const std::vector<std::string>& files, const FrictionInputOptions& options) {
  FrictionInput in = read_friction_input(files, options);
  for (auto& [file, sha256] : in.inputs) sha256 = sha256_file(file);
  return in;
}

void ModelOptions::add_to(CLI::App& app, const char* help) { app.add_option("--model", file, help); }

std::optional<LoadedModel> LoadedModel::read(const ModelOptions& options, const char* table) {
  if (options.file.empty()) return std::nullopt;
  LoadedModel m{options.file, "", read_model_file(options.file)};
  m.sha256 = sha256_file(options.file);
  const bool has = table == std::string_view("friction") ? m.model.has_friction : m.model.has_thermal;
  if (!has)
    throw InputError(m.file, 0, 0,
                     table == std::string_view("friction")
                         ? "expected a [friction] table (the calibrated friction law); this model has only [thermal] "
                           "(calibrate a folder with friction logs, friction*.csv)"
                         : "expected a [thermal] table (the calibrated rail model); this model has only [friction] "
                           "(calibrate a folder with a thermal manifest, thermal*.toml)");
  return m;
}

void LoadedModel::refuse(const std::vector<std::string>& given, const std::string& what) const {
  if (given.empty()) return;
  const std::string names = fmt::format("{}", fmt::join(given, ", "));
  throw InvalidParameter("--model", fmt::format("{} gives {}; {} cannot be given with it (leave out {} or --model)", file,
                                                what, names, names));
}

void LoadedModel::record_into(nlohmann::json& record) const {
  nlohmann::json inputs = nlohmann::json::array();
  for (const auto& [f, hash] : model.inputs) inputs.push_back({{"file", f}, {"sha256", hash}});
  const nlohmann::json this_file = {{"file", file}, {"sha256", sha256}};
  record["inputs"] = nlohmann::json::array({this_file});
  record["model"] = {{"file", file},
                     {"sha256", sha256},
                     {"set", model.set},
                     {"lmcal_version", model.lmcal_version},
                     {"command", model.command},
                     {"inputs", inputs}};
}

void add_assignments(CLI::App& app, const char* name, std::map<std::string, double>& values, const char* help) {
  app.add_option_function<std::vector<std::string>>(
         name,
         [&values, name](const std::vector<std::string>& items) {
           for (const std::string& item : items) {
             const auto eq = item.find('=');
             if (eq == std::string::npos)
               throw InvalidParameter(name, fmt::format("'{}' is not NAME=VALUE", item));
             values[item.substr(0, eq)] = parse_number(name, std::string_view(item).substr(eq + 1), "NAME=VALUE with a number");
           }
         },
         help)
      ->delimiter(',');
}

void add_uncertainty_options(CLI::App& app, FitOptions& fit) {
  add_choice(app, "--covariance", fit.covariance,
             "Covariance the intervals quote: auto (by the data's structure), iid, hac, cluster or bootstrap", "METHOD",
             kCovarianceMethods);
  app.add_option("--bootstrap", fit.bootstrap, "Cluster-bootstrap replicates (runs resampled; 0: none)")
      ->check(up_to_limit(0, static_cast<double>(io::kMaxBootstrapReplicates)))
      ->capture_default_str();
  add_choice(app, "--profile", fit.profile, "Profile-likelihood intervals: auto (where the linear one is unreliable), all or none",
             "MODE", kProfileModes);
}

CLI::Validator at_least(double low) {
  return CLI::Validator(
      [low](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v)) return fmt::format("expected a number, got '{}'", text);
        return v >= low ? "" : fmt::format("{} is below {:g}: expected a value of at least {:g}", text, low, low);
      },
      "");
}

CLI::Validator up_to_limit(double low, double high) {
  return CLI::Validator(
      [low, high](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v)) return fmt::format("expected a number, got '{}'", text);
        if (v >= low && v <= high) return "";
        return fmt::format("{} is {} {:g}: expected a value from {:g} to {:g} (docs/formats.md#limits)", text,
                           v < low ? "below" : "above", v < low ? low : high, low, high);
      },
      "");
}

CLI::Validator inside(double low, double high) {
  return CLI::Validator(
      [low, high](std::string& text) -> std::string {
        double v = 0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v)) return fmt::format("expected a number, got '{}'", text);
        return v > low && v < high ? "" : fmt::format("{} is outside ({:g}, {:g}): expected a value strictly between", text, low, high);
      },
      "");
}

void add_list(CLI::App& app, const char* name, std::vector<double>& values, const char* help) {
  app.add_option_function<std::string>(
      name, [&values, name](const std::string& text) { values = parse_list(name, text); }, help);
}

std::vector<double> or_catalog(const std::vector<double>& given, const GuideSpec& spec,
                               std::optional<double> GuideSpec::*field, const char* name) {
  if (!given.empty()) return given;
  return {require(spec, field, name)};
}

void ThermalModelOptions::add_to(CLI::App& app, ThermalFitOptions& fit) {
  app.add_option("--heat", heat, "Heat rate: auto, friction (law) or measured (start_friction_N x V, else the run mean mean_friction_N x V)")->capture_default_str();
  completes(app.add_option("--source", source, "Heat source model: paper, averaged or moving"), {"paper", "averaged", "moving"})
      ->capture_default_str();
  completes(app.add_option("--scheme", scheme, "Time scheme: backward-euler (be) or crank-nicolson (cn)"),
            {"backward-euler", "be", "crank-nicolson", "cn"})
      ->capture_default_str();
  // The numeric settings, each with how to copy it (copy_given).
  const auto numeric = [&](CLI::Option* option, auto member) {
    numeric_.emplace_back(option, [member](const ThermalFitOptions& from, ThermalFitOptions& to) { to.*member = from.*member; });
  };
  numeric(app.add_option("--segments", fit.half_rail_segments, "Segments on the half rail")
              ->check(up_to_limit(1, io::kMaxRailSegments))
              ->capture_default_str(),
          &ThermalFitOptions::half_rail_segments);
  numeric(app.add_option("--dt", fit.time_step_s, "Time step, s")->capture_default_str(), &ThermalFitOptions::time_step_s);
  numeric(app.add_option("--every", fit.every, "Fit every n-th record (the paper kept every 120th)")->capture_default_str(),
          &ThermalFitOptions::every);
  numeric(app.add_option("--ambient", fit.ambient, "Ambient: mean of the ambient sensors, or a column name")->capture_default_str(),
          &ThermalFitOptions::ambient);
  // What is held, freed and where it starts: the same for a fit and a diagnosis.
  numeric(app.add_option("--alpha-start", fit.alpha_start, "Start value of alpha")->capture_default_str(),
          &ThermalFitOptions::alpha_start);
  numeric(app.add_flag("--fit-h", fit.fit_h, "Also fit the convection coefficient h (one for all runs)"), &ThermalFitOptions::fit_h);
  numeric(app.add_option("--h", fit.h_W_m2K, "Convection coefficient (held there; the start value with --fit-h), W/m2K")
              ->capture_default_str(),
          &ThermalFitOptions::h_W_m2K);
  numeric(app.add_flag("--fit-initial", fit.fit_initial_temperature, "Also fit the initial rail temperature of each run"),
          &ThermalFitOptions::fit_initial_temperature);
}

void ThermalModelOptions::add_offsets(CLI::App& app, ThermalFitOptions& fit) {
  add_choice(app, "--offsets", fit.offsets,
             "Thermocouple offsets: auto (fitted for a run that starts isothermal, at the ambient), fit or hold", "MODE",
             kThermalOffsets);
}

void ThermalModelOptions::add_friction_file(CLI::App& app) {
  app.add_option("--friction", friction_fit, "Friction fit JSON (lmcal fit friction) for the heat rate");
}

void ThermalModelOptions::copy_given(const ThermalFitOptions& from, ThermalFitOptions& to) const {
  for (const auto& [option, copy] : numeric_)
    if (option->count() > 0) copy(from, to);
}

void ThermalModelOptions::apply(ThermalFitOptions& fit, std::vector<std::pair<std::string, std::string>>& inputs) const {
  fit.source = parse_source_model(source);
  fit.scheme = parse_time_scheme(scheme);
  fit.heat = parse_heat_input(heat, "--heat");
  if (!friction_fit.empty()) {
    read_friction_fit(friction_fit, fit);
    inputs.emplace_back(friction_fit, sha256_file(friction_fit));
  }
}


void add_friction_constant_options(CLI::App& app, FrictionConstantOptions& o) {
  app.add_option("--free", o.free, "Constants to fit (default all): k1,k2,mu_st,v_st_m_s,mu_v,beta_per_K,f0")->delimiter(',');
  add_assignments(app, "--fix", o.fixed, "Hold a constant at a value: --fix k2=0.03");
  add_assignments(app, "--start", o.start, "Start value: --start mu_st=1 (default: the paper's)");
  app.add_option("--bound", o.bounds, "Bounds: --bound k1=0:1 (repeatable)");
  completes(app.add_option("--run-offsets", o.run_offsets,
                 "The load cell's zero per run: auto (random with two runs or more and no robust loss; the default), none, "
                 "fixed (free, profiled) or random (a run intercept whose variance is estimated; keeps what changes only "
                 "between runs informative)"),
            enum_names(kRunOffsets));
  completes(app.add_option("--law-temperature", o.temperature,
                 "The temperature the law sees: block-mean (the default: each run's mean logged temperature at one setting, "
                 "which averages the thermometer's noise out instead of flattening the law's temperature dependence) or "
                 "logged (each sample's own)"),
            enum_names(kFrictionTemperatures));
}

void apply_friction_constant_options(const FrictionConstantOptions& o, FrictionFitOptions& f) {
  if (!o.free.empty()) {
    f.free.fill(false);
    for (const auto& name : o.free) f.free[friction_constant_index("--free", name)] = true;
  }
  for (const auto& [name, value] : o.start) fittable_constant(f.start, friction_constant_index("--start", name)) = value;
  for (const auto& [name, value] : o.fixed) {
    const std::size_t j = friction_constant_index("--fix", name);
    fittable_constant(f.start, j) = value;
    f.free[j] = false;
  }
  for (const auto& item : o.bounds) {
    const auto eq = item.find('='), colon = item.find(':', eq == std::string::npos ? 0 : eq);
    if (eq == std::string::npos || colon == std::string::npos)
      throw InvalidParameter("--bound", fmt::format("'{}' is not NAME=LOW:HIGH", item));
    const auto range = parse_list("--bound", item.substr(eq + 1, colon - eq - 1) + "," + item.substr(colon + 1));
    f.bounds[friction_constant_index("--bound", item.substr(0, eq))] = {range[0], range[1]};
  }
  if (!o.run_offsets.empty()) f.run_offsets = parse_run_offsets(o.run_offsets, "--run-offsets");
  if (!o.temperature.empty()) f.temperature = parse_friction_temperature(o.temperature, "--law-temperature");
}

}  // namespace lmcal::cli
