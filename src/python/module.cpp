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
#include "module.hpp"

namespace lmcal::python {

// ---- values in and out ------------------------------------------------------------------------

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

void write_files(const fs::path& dir, const Files& files, const std::vector<std::string>& replaced) {
  OutputSet out;
  for (const std::string& name : replaced) out.remove(dir / name);
  for (const auto& [name, contents] : files) out.add(dir / name, contents);
  out.commit();
}

// ---- progress and interruption ----------------------------------------------------------------

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

}  // namespace lmcal::python

PYBIND11_MODULE(_lmcal, m) {
  using namespace lmcal;
  using namespace lmcal::python;
  m.doc() = "lmcal's compiled core; use the package `lmcal`";
  m.attr("__version__") = LMCAL_VERSION;
  register_errors(m);
  bind_loaders(m);
  bind_fits(m);
  bind_simulation(m);
}
