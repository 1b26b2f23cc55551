// The Python module's loaders: friction logs from files, a manifest or columns, thermal data
// sets and a run's trace from columns (module.hpp).
#include "module.hpp"

namespace lmcal::python {

RawFrictionOptions raw_options(const py::dict& given, std::vector<std::string>* names) {
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

namespace {

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

}  // namespace

void bind_loaders(py::module_& m) {
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
}

}  // namespace lmcal::python
