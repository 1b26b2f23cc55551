// The Python module's shared parts: the values its files pass each other and the handles a
// result is held in. module.cpp registers the module and its errors and turns values in and
// out; loaders.cpp binds the loaders (FrictionData, ThermalData), fits.cpp the fits, diagnoses
// and calibration, simulation.cpp the friction law, the simulation, the rig and the prediction.
#pragma once

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

using Inputs = std::vector<std::pair<std::string, std::string>>;  // file -> sha256
using Files = std::vector<std::pair<std::string, std::string>>;   // output name -> contents

// ---- values in and out (module.cpp) -----------------------------------------------------------

template <class T>
py::array_t<T> array(const std::vector<T>& v) {
  return py::array_t<T>(static_cast<py::ssize_t>(v.size()), v.data());
}

// The covariance and the parameters of a fit, for NumPy.
py::dict fit_arrays(const FitResult& fit);
// `replaced`: names an earlier set may have written there that this one replaces by nothing.
void write_files(const fs::path& dir, const Files& files, const std::vector<std::string>& replaced = {});
// A Python callable as the library's Progress, callable from any thread; the callable's
// reference is dropped with the GIL held. Without a callable it still checks for Ctrl-C.
Progress python_progress(const py::object& callback);

// ---- loaders (loaders.cpp) --------------------------------------------------------------------

// A friction log with the files it came from and their SHA-256 (recorded in a fit's JSON).
struct FrictionData {
  std::shared_ptr<const FrictionLog> log;
  Inputs inputs;
};

struct ThermalData {
  std::shared_ptr<const ThermalDataSet> set;
  Inputs inputs;
};

// The raw-log settings of a `raw=` dict, validated (the keys it gave appended to `names`).
RawFrictionOptions raw_options(const py::dict& given, std::vector<std::string>* names = nullptr);
// The user's catalog, when a file is given.
std::optional<GuideCatalog> user_catalog(const std::optional<std::string>& file);

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

// ---- the friction law at given conditions (simulation.cpp) ------------------------------------

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

// The law at every row of equally long condition arrays (broadcast in __init__.py): velocity_m_s,
// load_N, preload_um, block_length_mm, temperature_C, viscosity40_mm2_s, direction, and if given
// acceleration_m_s2, position_m, distance_since_reversal_m (0 otherwise: what the effects of a
// trajectory or a raw log use).
py::array_t<double> friction_law_at(const FrictionLaw& law, const py::dict& columns);

// ---- fits, diagnoses and calibration (fits.cpp) -----------------------------------------------

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

struct FrictionDiagnosisHandle {
  std::shared_ptr<const FrictionDiagnosis> result;
  std::string json() const { return friction_diagnosis_json(*result); }
};
struct ThermalDiagnosisHandle {
  std::shared_ptr<const ThermalDiagnosis> result;
  std::string json() const { return thermal_diagnosis_json(*result); }
};

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

// ---- the module's parts, in the order they are bound ------------------------------------------

void register_errors(py::module_& m);  // module.cpp
void bind_loaders(py::module_& m);     // loaders.cpp
void bind_fits(py::module_& m);        // fits.cpp
void bind_simulation(py::module_& m);  // simulation.cpp

}  // namespace lmcal::python
