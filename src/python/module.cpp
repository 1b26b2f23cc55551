// The compiled half of the Python package `lmcal` (src/python/lmcal/__init__.py is the
// other): loaders, fits, diagnoses, calibration and simulation over the C++ library, each
// result held in a handle that gives its JSON (the CLI's, byte for byte the same numbers),
// its one-screen summary, its output files and its arrays as NumPy arrays.
//
// Threads: every long call releases the GIL; a progress callback takes it back to call into
// Python (and checks for Ctrl-C, which ends the call with KeyboardInterrupt). Errors: the
// library's InputError and InvalidParameter arrive as lmcal.InputError and
// lmcal.InvalidParameterError, both ValueErrors, with their file/line/column or parameter;
// about columns from Python, with the row and the column's name (ColumnsError, ConditionError).
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <fmt/format.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <random>
#include <regex>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include "lmcal/calibrate/calibration.hpp"
#include "lmcal/diagnose/friction_diagnosis.hpp"
#include "lmcal/diagnose/thermal_diagnosis.hpp"
#include "lmcal/error.hpp"
#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/fit/thermal_fit.hpp"
#include "lmcal/io/atomic_file.hpp"
#include "lmcal/io/catalog.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/io/hash.hpp"
#include "lmcal/io/thermal_run.hpp"
#include "lmcal/io/units.hpp"
#include "lmcal/models/friction_effects.hpp"
#include "lmcal/models/heat_source.hpp"
#include "lmcal/models/rail_thermal.hpp"
#include "lmcal/predict/prediction.hpp"
#include "lmcal/report/calibration.hpp"
#include "lmcal/report/html_report.hpp"
#include "lmcal/rig/virtual_rig.hpp"

namespace py = pybind11;
namespace fs = std::filesystem;

namespace lmcal::python {

namespace {

using Inputs = std::vector<std::pair<std::string, std::string>>;  // file -> sha256
using Files = std::vector<std::pair<std::string, std::string>>;   // output name -> contents

// ---- values in and out ------------------------------------------------------------------------

template <class T>
py::array_t<T> array(const std::vector<T>& v) {
  return py::array_t<T>(static_cast<py::ssize_t>(v.size()), v.data());
}

// The covariance and the parameters of a fit, for NumPy.
py::dict fit_arrays(const FitResult& fit) {
  std::vector<std::string> names;
  std::vector<double> values, se;
  std::vector<bool> per_run;
  for (const auto& p : fit.parameters) {
    names.push_back(p.name);
    values.push_back(p.value);
    se.push_back(p.se);
    per_run.push_back(p.per_run);
  }
  py::dict d;
  d["names"] = names;
  d["per_run"] = per_run;
  d["values"] = array(values);
  d["se"] = array(se);
  d["covariance"] = py::cast(Eigen::MatrixXd(fit.covariance));
  d["correlation"] = py::cast(Eigen::MatrixXd(fit.correlation));
  return d;
}

// `replaced`: names an earlier set may have written there that this one replaces by nothing.
void write_files(const fs::path& dir, const Files& files, const std::vector<std::string>& replaced = {}) {
  OutputSet out;
  for (const std::string& name : replaced) out.remove(dir / name);
  for (const auto& [name, contents] : files) out.add(dir / name, contents);
  out.commit();
}

// ---- progress and interruption ----------------------------------------------------------------

// A Python callable as the library's Progress, callable from any thread; the callable's
// reference is dropped with the GIL held. Without a callable it still checks for Ctrl-C.
Progress python_progress(const py::object& callback) {
  std::shared_ptr<py::object> held(new py::object(callback), [](py::object* o) {
    py::gil_scoped_acquire gil;
    delete o;
  });
  return [held](const std::string& what, std::size_t done, std::size_t total) {
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
    if (!held->is_none()) (*held)(what, done, total);
  };
}

// ---- loaders ----------------------------------------------------------------------------------

// A friction log with the files it came from and their SHA-256 (recorded in a fit's JSON).
struct FrictionData {
  std::shared_ptr<const FrictionLog> log;
  Inputs inputs;
};

RawFrictionOptions raw_options(const py::dict& given, std::vector<std::string>* names = nullptr) {
  RawFrictionOptions raw;
  for (const auto& [key, value] : given) {
    const auto name = key.cast<std::string>();
    if (name == "force_sign") raw.force_sign = parse_force_sign(value.cast<std::string>());
    else if (name == "duplicate_times") raw.duplicate_times = parse_duplicate_times(value.cast<std::string>());
    else if (name == "max_acceleration_m_s2") raw.max_acceleration_m_s2 = value.cast<double>();
    else if (name == "settling_s") raw.settling_s = value.cast<double>();
    else if (name == "min_speed_m_s") raw.min_speed_m_s = value.cast<double>();
    else if (name == "velocity_tolerance") raw.velocity_tolerance = value.cast<double>();
    else if (name == "min_plateau_samples") raw.min_plateau_samples = value.cast<std::size_t>();
    else if (name == "velocity_window") raw.velocity_window = value.cast<std::size_t>();
    else if (name == "moving_mass_kg") raw.moving_mass_kg = value.cast<double>();
    else if (name == "skip_lines") raw.skip_lines = value.cast<std::size_t>();
    else if (Drive::is_key(name)) raw.drive.set(name, value.cast<double>());
    else if (name == "segmentation") raw.segmentation = parse_raw_segmentation(value.cast<std::string>());
    else if (name == "trajectory_window") raw.trajectory_window = value.cast<std::size_t>();
    else if (name == "presliding_m") raw.presliding_m = value.cast<double>();
    else if (name == "axis_incline_deg") raw.axis_incline_deg = value.cast<double>(), raw.incline_stated = true;
    else if (name == "force_sensor") raw.force_sensor = parse_force_sensor(value.cast<std::string>());
    else
      throw InvalidParameter("raw", fmt::format("unknown segmentation setting '{}'; expected force_sign, duplicate_times, "
                                                "max_acceleration_m_s2, settling_s, min_speed_m_s, velocity_tolerance, "
                                                "min_plateau_samples, velocity_window, moving_mass_kg, segmentation, "
                                                "trajectory_window, presliding_m, axis_incline_deg, force_sensor, skip_lines or a drive's "
                                                "lead_mm, pinion_radius_mm, gear_ratio, efficiency, rotor_inertia_kg_m2, "
                                                "nominal_torque_Nm",
                                                name));
    if (names) names->push_back(name);
  }
  raw.validate();
  return raw;
}

std::optional<GuideCatalog> user_catalog(const std::optional<std::string>& file) {
  if (!file) return std::nullopt;
  return load_catalog(*file);
}

FrictionData load_friction_files(const std::vector<std::string>& files, const py::dict& raw_given) {
  const RawFrictionOptions raw = raw_options(raw_given);
  std::vector<fs::path> paths(files.begin(), files.end());
  FrictionData data;
  {
    py::gil_scoped_release release;
    data.log = std::make_shared<FrictionLog>(load_friction_logs(paths, raw));
    for (const auto& f : files) data.inputs.emplace_back(f, sha256_file(f));
  }
  return data;
}

FrictionData load_friction_manifest(const std::string& manifest, const std::optional<std::string>& catalog,
                                    const py::dict& raw_given, bool allow_outside_root) {
  std::vector<std::string> given;
  const RawFrictionOptions raw = raw_options(raw_given, &given);
  FrictionData data;
  py::gil_scoped_release release;
  const auto user = user_catalog(catalog);
  FrictionDataSet set = load_friction_dataset(manifest, user ? &*user : nullptr, raw, given, {.allow_outside = allow_outside_root});
  data.inputs.emplace_back(manifest, sha256_file(manifest));
  for (const auto& f : set.files) data.inputs.emplace_back(f.string(), sha256_file(f));
  data.log = std::make_shared<FrictionLog>(std::move(set.log));
  return data;
}

// Columns (validated in __init__.py: equal lengths, numbers without NaN, text as str) through
// the CSV loader, so that they follow every rule of a file: units from the names, ranges,
// run and guide names. Written to a private temporary file; an InputError about it is told
// again as a ColumnsError: the column's name and the row (0-based) in place of the file's
// line and character.
std::string csv_cell_text(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

// lmcal.InputError with `file` "columns", `row` (0-based; none for the header) and `column`
// (the column's name; "" when the loader's message names none).
class ColumnsError : public InputError {
 public:
  ColumnsError(std::optional<std::size_t> row, std::string column, const std::string& what)
      : InputError("columns", 0, 0, where(row, column) + what), row_(row), column_(std::move(column)) {}
  std::optional<std::size_t> row() const { return row_; }
  const std::string& column_name() const { return column_; }

 private:
  static std::string where(std::optional<std::size_t> row, const std::string& column) {
    std::string at = column.empty() ? "" : fmt::format("column '{}'", column);
    if (row) at += fmt::format("{}row {}", at.empty() ? "" : ", ", *row);
    return at.empty() ? at : at + ": ";
  }
  std::optional<std::size_t> row_;
  std::string column_;
};

// The field (0-based) of a CSV line that character `column` (1-based) falls in.
std::size_t field_at(std::string_view line, long column) {
  std::size_t field = 0;
  bool quoted = false;
  for (std::size_t i = 0; i + 1 < static_cast<std::size_t>(column) && i < line.size(); ++i) {
    if (line[i] == '"') quoted = !quoted;
    else if (line[i] == ',' && !quoted) ++field;
  }
  return field;
}

// The column (of `names`, written as `text`) an error of the loader is about: the field of the
// character it points to (in the header only one the message names: a missing column is none of
// those there), else the one the message starts with ("load_N = -5 is negative"); "" if none.
std::string column_of(const InputError& e, const std::string& message, const std::string& text,
                      const std::vector<std::string>& names) {
  if (e.line() > 0 && e.column() > 0) {
    std::size_t start = 0;
    for (long l = 1; l < e.line() && start != std::string::npos; ++l) start = text.find('\n', start) + 1;
    const std::string_view line = std::string_view(text).substr(start, text.find('\n', start) - start);
    const std::size_t field = field_at(line, e.column());
    if (field < names.size() && (e.line() > 1 || message.find("'" + names[field] + "'") != std::string::npos))
      return names[field];
  }
  for (const auto& name : names)
    if (message.starts_with(name + " = ")) return name;
  return "";
}

// A message's other lines of the temporary file ("not later than the previous row's (line 5)") as
// the rows they are ("(row 3)"): line 1 is the header, line L > 1 row L - 2.
std::string lines_as_rows(const std::string& message) {
  static const std::regex other_line(R"(\(line (\d+)\))");
  std::string out;
  auto at = message.cbegin();
  for (std::sregex_iterator it(message.begin(), message.end(), other_line), end; it != end; ++it) {
    out.append(at, (*it)[0].first);
    const long line = std::stol((*it)[1].str());
    out += line > 1 ? fmt::format("(row {})", line - 2) : "(the header)";
    at = (*it)[0].second;
  }
  return out.append(at, message.cend());
}

// An InputError about the temporary file `text` of `names` as a ColumnsError.
ColumnsError columns_error(const InputError& e, const std::string& text, const std::vector<std::string>& names) {
  const std::string where = e.line() > 0 ? fmt::format("{}:{}", e.file(), e.line()) : e.file();
  std::string message = e.what();
  const std::size_t colon = message.find(": ", where.size());
  message = colon == std::string::npos ? message : message.substr(colon + 2);
  std::string column;
  if (message.starts_with("column '")) {  // the loader named it: said once, in front
    if (const std::size_t end = message.find("': "); end != std::string::npos) {
      column = message.substr(8, end - 8);
      message = message.substr(end + 3);
    }
  }
  if (column.empty()) column = column_of(e, message, text, names);
  return ColumnsError(e.line() > 1 ? std::optional<std::size_t>(e.line() - 2) : std::nullopt, column,
                      lines_as_rows(message));
}

template <class Load>
auto load_columns(const std::vector<std::string>& names, const std::vector<py::object>& columns, const char* what,
                  Load&& load) {
  LMCAL_ASSERT(names.size() == columns.size(), "one name per column");
  std::string text;
  for (std::size_t c = 0; c < names.size(); ++c) text += (c ? "," : "") + csv_cell_text(names[c]);
  text += '\n';
  std::vector<std::variant<py::array_t<double>, std::vector<std::string>>> cells;
  std::size_t rows = 0;
  for (const auto& column : columns) {
    if (py::isinstance<py::list>(column)) {
      cells.emplace_back(column.cast<std::vector<std::string>>());
      rows = std::get<1>(cells.back()).size();
    } else {
      cells.emplace_back(column.cast<py::array_t<double, py::array::c_style | py::array::forcecast>>());
      rows = static_cast<std::size_t>(std::get<0>(cells.back()).size());
    }
  }
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < cells.size(); ++c) {
      if (c) text += ',';
      if (const auto* numbers = std::get_if<0>(&cells[c])) text += fmt::format("{}", numbers->at(r));
      else {
        const std::string& cell = std::get<1>(cells[c])[r];
        if (cell.find_first_of("\n\r") != std::string::npos) throw ColumnsError(r, names[c], "a line break inside a name");
        text += csv_cell_text(cell);
      }
    }
    text += '\n';
  }
  static std::atomic<unsigned> counter{0};
  const fs::path file = fs::temp_directory_path() /
                        fmt::format("lmcal-{}-{}-{}.csv", what, std::random_device{}(), counter.fetch_add(1));
  struct Remove {
    fs::path file;
    ~Remove() {
      std::error_code ec;
      fs::remove(file, ec);
    }
  } remove{file};
  {
    std::ofstream out(file, std::ios::binary);
    out << text;
    if (!out) throw std::runtime_error("cannot write a temporary file in " + file.parent_path().string());
  }
  try {
    py::gil_scoped_release release;
    return load(file);
  } catch (const InputError& e) {
    if (e.file() != file.string()) throw;
    throw columns_error(e, text, names);
  }
}

FrictionData friction_log_from_columns(const std::vector<std::string>& names, const std::vector<py::object>& columns,
                                       const py::dict& raw_given) {
  const RawFrictionOptions raw = raw_options(raw_given);
  FrictionData data;
  data.log = std::make_shared<FrictionLog>(
      load_columns(names, columns, "friction", [&](const fs::path& file) {
        FrictionLog log = load_friction_log(file, raw);
        for (auto& report : log.reports) report.file = "columns";
        return log;
      }));
  return data;
}

struct ThermalData {
  std::shared_ptr<const ThermalDataSet> set;
  Inputs inputs;
};

ThermalData load_thermal(const std::string& manifest, const std::optional<std::string>& catalog, bool allow_outside_root) {
  ThermalData data;
  py::gil_scoped_release release;
  const auto user = user_catalog(catalog);
  auto set = std::make_shared<ThermalDataSet>(
      load_thermal_dataset(manifest, user ? &*user : nullptr, {.allow_outside = allow_outside_root}));
  data.inputs.emplace_back(manifest, sha256_file(manifest));
  if (!set->catalog_file.empty()) data.inputs.emplace_back(set->catalog_file.string(), sha256_file(set->catalog_file));
  for (const auto& run : set->runs) data.inputs.emplace_back(run.file.string(), sha256_file(run.file));
  data.set = std::move(set);
  return data;
}

// A copy of `data` with one run's trace replaced by columns (time_s, ambient…, tc…): the same
// thermocouple and ambient columns as the run's file had, so the manifest's sensor positions
// still name them.
ThermalData with_trace(const ThermalData& data, const std::string& run_id, const std::vector<std::string>& names,
                       const std::vector<py::object>& columns) {
  auto set = std::make_shared<ThermalDataSet>(*data.set);
  auto run = std::find_if(set->runs.begin(), set->runs.end(), [&](const ThermalRun& r) { return r.id == run_id; });
  if (run == set->runs.end()) throw InvalidParameter("run", fmt::format("no run '{}' in the data set", run_id));
  ThermalTrace trace = load_columns(names, columns, "thermal", [](const fs::path& file) { return load_thermal_trace(file); });
  const auto channel_names = [](const std::vector<TemperatureChannel>& channels) {
    std::vector<std::string> out;
    for (const auto& c : channels) out.push_back(c.name);
    return out;
  };
  if (channel_names(trace.rail) != channel_names(run->trace.rail) ||
      channel_names(trace.ambient) != channel_names(run->trace.ambient))
    throw py::value_error(fmt::format("columns of run '{}': expected the columns of its file ({}, {}), in that order",
                                      run_id, fmt::join(channel_names(run->trace.ambient), ", "),
                                      fmt::join(channel_names(run->trace.rail), ", ")));
  for (std::size_t s = 0; s < trace.rail.size(); ++s) trace.rail[s].name = run->trace.rail[s].name;
  trace.report.file = "columns";
  run->trace = std::move(trace);
  ThermalData out{std::move(set), {}};
  for (const auto& input : data.inputs)
    if (input.first != run->file.string()) out.inputs.push_back(input);
  return out;
}

// ---- the friction law at given conditions ----------------------------------------------------

// A condition handed to the friction law that it refuses: lmcal.InvalidParameterError with
// `parameter` (the condition's name) and `row` (0-based, of the flattened conditions).
struct ConditionError : std::invalid_argument {
  ConditionError(std::string parameter, std::size_t row, const std::string& what)
      : std::invalid_argument(fmt::format("row {}: {}", row, what)), parameter(std::move(parameter)), row(row) {}
  std::string parameter;
  std::size_t row;
};

// A friction law as the Python module evaluates it: constants, effects and empirical terms
// (at steady state, as `lmcal simulate friction --model` evaluates them).
struct FrictionLaw {
  FrictionConstants<double> constants;
  FrictionEffects<double> effects;
  std::vector<FrictionTerm> terms;
};

// ---- fits -------------------------------------------------------------------------------------

struct FrictionFit {
  std::shared_ptr<const FrictionFitResult> result;
  std::shared_ptr<const FrictionLog> log;
  FrictionFitOptions options;
  FitProvenance provenance;

  std::string json() const { return friction_fit_json(*result, options, provenance); }
  Files files() const { return friction_fit_files(*result, *log, options, provenance); }
  py::dict arrays() const {
    py::dict d = fit_arrays(result->fit);
    d["measured_N"] = array(log->friction_N);
    d["predicted_N"] = array(result->predicted_N);
    d["sigma_N"] = array(result->sigma_N);
    d["run"] = array(log->run);
    d["run_names"] = result->runs;
    d["run_offset_N"] = array(result->run_offset_N);
    return d;
  }
  // The fitted law: constants (ν's reference temperature the fit's), effects, empirical terms.
  FrictionLaw law() const {
    FrictionConstants<double> k = result->constants();
    k.T_ref_C = options.start.T_ref_C;
    return {k, result->effects(), result->terms};
  }
  // The conditions the log did not give (a combination law's setup, the temperature), each
  // with the value the fit took for it: condition -> value.
  std::map<std::string, double> unlogged_conditions() const {
    const std::map<std::string, const std::vector<double>*> columns{{"load_N", &log->load_N},
                                                                     {"preload_um", &log->preload_um},
                                                                     {"block_length_mm", &log->block_length_mm},
                                                                     {"temperature_C", &log->temperature_C}};
    std::map<std::string, double> out;
    for (const auto& name : log->law.not_logged())
      if (const auto it = columns.find(name); it != columns.end() && !it->second->empty()) out[name] = it->second->front();
    return out;
  }
};

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

struct ThermalFit {
  std::shared_ptr<const ThermalFitResult> result;
  std::shared_ptr<const ThermalDataSet> data;
  ThermalFitOptions options;
  Inputs inputs;
  std::vector<std::string> command;
  std::string name;

  std::string json() const { return thermal_fit_json(*result, options, inputs, command, name); }
  Files files() const { return thermal_fit_files(*result, options, inputs, command, name); }
  py::dict arrays() const {
    py::dict d = fit_arrays(result->joint);
    std::vector<double> run, sensor, time, measured, simulated;
    for (const auto& s : result->samples) {
      run.push_back(static_cast<double>(s.run));
      sensor.push_back(static_cast<double>(s.sensor));
      time.push_back(s.time_s);
      measured.push_back(s.measured_C);
      simulated.push_back(s.simulated_C);
    }
    py::dict samples;
    samples["run"] = array(run).attr("astype")("int64");
    samples["sensor"] = array(sensor).attr("astype")("int64");
    samples["time_s"] = array(time);
    samples["measured_C"] = array(measured);
    samples["simulated_C"] = array(simulated);
    d["samples"] = samples;
    std::vector<std::string> runs;
    for (const auto& r : result->runs) runs.push_back(r.id);
    d["run_names"] = runs;
    d["sensor_names"] = result->sensor_names;
    return d;
  }
};

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

// ---- diagnoses and calibration ----------------------------------------------------------------

struct FrictionDiagnosisHandle {
  std::shared_ptr<const FrictionDiagnosis> result;
  std::string json() const { return friction_diagnosis_json(*result); }
};
struct ThermalDiagnosisHandle {
  std::shared_ptr<const ThermalDiagnosis> result;
  std::string json() const { return thermal_diagnosis_json(*result); }
};

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

struct CalibrationHandle {
  std::shared_ptr<const Calibration> c;

  std::string json() const { return calibration_json(*c); }
  Files files() const { return calibration_outputs(*c); }
  // c.inputs: the friction logs first, then the thermal files (as calibration_outputs splits them).
  Inputs friction_inputs() const { return {c->inputs.begin(), c->inputs.begin() + static_cast<std::ptrdiff_t>(c->set.friction_logs.size())}; }
  Inputs thermal_inputs() const { return {c->inputs.begin() + static_cast<std::ptrdiff_t>(c->set.friction_logs.size()), c->inputs.end()}; }
  std::optional<FrictionFit> friction(bool calibrated) const {
    const auto& result = calibrated ? c->calibrated.friction : c->friction;
    if (!result || !c->friction_log) return std::nullopt;
    return FrictionFit{{c, &*result},
                       {c, &*c->friction_log},
                       calibrated ? c->calibrated.friction_options : c->friction_options,
                       {calibrated ? "calibrated_friction" : "friction", friction_inputs(), c->command}};
  }
  std::optional<ThermalFit> thermal(bool calibrated) const {
    const auto& result = calibrated ? c->calibrated.thermal : c->thermal;
    if (!result || !c->thermal_data) return std::nullopt;
    return ThermalFit{{c, &*result},
                      {c, &*c->thermal_data},
                      calibrated ? c->calibrated.thermal_options : c->thermal_options,
                      thermal_inputs(),
                      c->command,
                      calibrated ? "calibrated_thermal" : "thermal"};
  }
};

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

// ---- simulation -------------------------------------------------------------------------------

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

// The law at every row of equally long condition arrays (broadcast in __init__.py): velocity_m_s,
// load_N, preload_um, block_length_mm, temperature_C, viscosity40_mm2_s, direction, and if given
// acceleration_m_s2, position_m, distance_since_reversal_m (0 otherwise: what the effects of a
// trajectory or a raw log use).
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

// ---- prediction -------------------------------------------------------------------------------

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

// ---- errors -----------------------------------------------------------------------------------

void register_errors(py::module_& m) {
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  static py::exception<InvalidParameter> invalid_parameter(m, "InvalidParameterError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    const auto raise = [](py::handle type, const char* what,
                          std::initializer_list<std::pair<const char*, py::object>> attributes) {
      py::object error = type(what);
      for (const auto& [name, value] : attributes) error.attr(name) = value;
      PyErr_SetObject(type.ptr(), error.ptr());
    };
    const auto optional = [](const auto& value) { return value ? py::cast(*value) : py::object(py::none()); };
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ColumnsError& e) {  // columns: the row and the column's name, no line
      raise(input_error, e.what(),
            {{"file", py::str(e.file())}, {"line", py::none()}, {"row", optional(e.row())},
             {"column", e.column_name().empty() ? py::object(py::none()) : py::str(e.column_name())}});
    } catch (const InputError& e) {
      raise(input_error, e.what(),
            {{"file", py::str(e.file())}, {"line", py::int_(e.line())}, {"column", py::int_(e.column())}, {"row", py::none()}});
    } catch (const InvalidParameter& e) {
      raise(invalid_parameter, e.what(),
            {{"parameter", py::str(e.parameter())}, {"row", py::none()}});
    } catch (const ConditionError& e) {
      raise(invalid_parameter, e.what(),
            {{"parameter", py::str(e.parameter)}, {"row", py::int_(e.row)}});
    }
  });
}

}  // namespace

}  // namespace lmcal::python

PYBIND11_MODULE(_lmcal, m) {
  using namespace lmcal;
  using namespace lmcal::python;
  m.doc() = "lmcal's compiled core; use the package `lmcal`";
  m.attr("__version__") = LMCAL_VERSION;
  register_errors(m);

  py::class_<FrictionData>(m, "FrictionData")
      .def("__len__", [](const FrictionData& d) { return d.log->size(); })
      .def_property_readonly("inputs", [](const FrictionData& d) { return d.inputs; })
      .def("columns",
           [](const FrictionData& d) {
             const FrictionLog& l = *d.log;
             py::dict c;
             c["run"] = array(l.run);
             c["guide"] = array(l.guide);
             c["time_s"] = array(l.time_s);
             c["velocity_m_s"] = array(l.velocity_m_s);
             c["load_N"] = array(l.load_N);
             c["preload_um"] = array(l.preload_um);
             c["block_length_mm"] = array(l.block_length_mm);
             c["temperature_C"] = array(l.temperature_C);
             c["viscosity40_mm2_s"] = array(l.viscosity40_mm2_s);
             c["direction"] = array(l.direction);
             c["friction_N"] = array(l.friction_N);
             return c;
           })
      .def_property_readonly("run_names", [](const FrictionData& d) { return d.log->run_names; })
      .def_property_readonly("guide_names", [](const FrictionData& d) { return d.log->guide_names; })
      .def("load_reports",
           [](const FrictionData& d) {
             py::list out;
             for (const auto& r : d.log->reports) {
               py::dict report;
               report["file"] = r.file;
               report["rows_read"] = r.rows_read;
               report["rows_kept"] = r.rows_kept;
               report["skipped"] = r.skipped;
               report["ignored_columns"] = r.ignored_columns;
               report["notes"] = r.notes;
               report["conversions"] = r.conversions;
               report["warnings"] = r.warnings;
               out.append(report);
             }
             return out;
           })
      .def("csv", [](const FrictionData& d) { return friction_log_csv(*d.log); });
  m.def("load_friction_files", &load_friction_files);
  m.def("load_friction_manifest", &load_friction_manifest);
  m.def("friction_log_from_columns", &friction_log_from_columns);

  py::class_<ThermalData>(m, "ThermalData")
      .def_property_readonly("inputs", [](const ThermalData& d) { return d.inputs; })
      .def_property_readonly("name", [](const ThermalData& d) { return d.set->name; })
      .def("runs", [](const ThermalData& d) {
        py::list runs;
        for (const ThermalRun& r : d.set->runs) {
          py::dict run;
          run["id"] = r.id;
          run["file"] = r.file.string();
          run["guide"] = r.guide;
          run["velocity_m_s"] = r.velocity_m_s;
          run["load_N"] = r.load_N;
          run["stroke_m"] = r.stroke_m;
          run["rail_length_m"] = r.rail_length_m;
          run["sensor_position_m"] = r.sensor_position_m;
          py::dict trace;
          trace["time_s"] = array(r.trace.time_s);
          for (const auto& c : r.trace.ambient) trace[py::str(c.name)] = array(c.values);
          for (const auto& c : r.trace.rail) trace[py::str(c.name)] = array(c.values);
          if (!r.trace.heat_rate_W.empty()) trace["heat_rate_W"] = array(r.trace.heat_rate_W);
          run["trace"] = trace;
          runs.append(run);
        }
        return runs;
      });
  m.def("load_thermal_manifest", &load_thermal);
  m.def("thermal_with_trace", &with_trace);

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
