// The friction log: its conditions and sensors in words, several files loaded as one log
// (each read apart where they do not bear on each other) and the log written as CSV. One
// file's reading: friction_file_loader.hpp.
#include "lmcal/io/friction_log.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <optional>

#include "io/csv_reader.hpp"
#include "io/friction_file_loader.hpp"
#include "io/friction_files.hpp"
#include "io/input_file.hpp"
#include "io/raw_friction.hpp"
#include "parallel_slices.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/csv_writer.hpp"
#include "lmcal/io/limits.hpp"

namespace lmcal {

namespace {

namespace fs = std::filesystem;
using detail::friction_reading::FileLoader;
using detail::friction_reading::header_of;
using detail::friction_reading::kDefaultViscosity40_mm2_s;
using detail::friction_reading::map_names;
using detail::friction_reading::NameIndex;
using detail::friction_reading::Spec;
using enum detail::friction_reading::Spec;

}  // namespace

std::string_view to_string(ForceSensor s) {
  switch (s) {
    case ForceSensor::load_cell: return "load_cell";
    case ForceSensor::motor_current: return "motor_current";
    case ForceSensor::torque_sensor: return "torque_sensor";
    case ForceSensor::unknown: break;
  }
  return "unknown";
}

ForceSensor parse_force_sensor(std::string_view name) {
  for (ForceSensor s : {ForceSensor::unknown, ForceSensor::load_cell, ForceSensor::motor_current, ForceSensor::torque_sensor})
    if (name == to_string(s)) return s;
  throw InvalidParameter("force_sensor", fmt::format("unknown sensor '{}': expected load_cell, motor_current, "
                                                     "torque_sensor or unknown",
                                                     name));
}

std::vector<std::string> FrictionLawConditions::not_logged() const {
  std::vector<std::string> out;
  if (!load) out.push_back(header_of(kLoad));
  if (!preload) out.push_back(preload_N ? header_of(kPreload) + " (only preload_N)" : header_of(kPreload));
  if (!block_length) out.push_back(header_of(kBlockLength));
  if (!temperature) out.push_back(header_of(kTemperature));
  return out;
}

std::string FrictionLawConditions::stated() const {
  std::vector<std::string> parts;
  if (load_N) parts.push_back(fmt::format("load {:g} N", *load_N));
  if (preload_um) {
    parts.push_back(preload_class ? fmt::format("preload {:g} µm (class {})", *preload_um, *preload_class)
                                  : fmt::format("preload {:g} µm", *preload_um));
  }
  if (preload_N) parts.push_back(fmt::format("preload {:g} N", *preload_N));
  if (block_length_mm) parts.push_back(fmt::format("block length {:g} mm", *block_length_mm));
  return parts.empty() ? std::string("no conditions given") : fmt::format("{}", fmt::join(parts, ", "));
}

double preload_class_um(std::string_view preload_class, std::string_view guide) {
  // The middle of each class's radial clearance, −µm (PHYSICS.md §1a; size 25's C0 is −4…−3).
  const bool size25 = guide.find(" 25") != std::string_view::npos;
  if (preload_class == "normal") return 1.5;
  if (preload_class == "C1") return 2.5;
  if (preload_class == "C0") return size25 ? 3.5 : 4.0;
  throw InvalidParameter("preload_class", fmt::format("unknown class '{}': expected normal, C1 or C0 (THK SRG/SRN)",
                                                      preload_class));
}

// Flattened: sixteen push_backs inlined (their capacity reserved by the loaders) rather than called.
[[gnu::flatten]] void FrictionLog::append(std::uint32_t run_index, std::uint32_t guide_index, double time,
                         const FrictionConditions<double>& c, double friction, double viscosity40,
                         std::uint32_t source_line) {
  run.push_back(run_index);
  guide.push_back(guide_index);
  time_s.push_back(time);
  velocity_m_s.push_back(c.velocity_m_s);
  load_N.push_back(c.load_N);
  preload_um.push_back(c.preload_um);
  block_length_mm.push_back(c.block_length_mm);
  temperature_C.push_back(c.temperature_C);
  friction_N.push_back(friction);
  viscosity40_mm2_s.push_back(viscosity40);
  direction.push_back(static_cast<std::int8_t>(c.direction));
  acceleration_m_s2.push_back(c.acceleration_m_s2);
  position_m.push_back(c.position_m);
  distance_since_reversal_m.push_back(c.distance_since_reversal_m);
  time_since_reversal_s.push_back(std::numeric_limits<double>::quiet_NaN());
  line.push_back(source_line);
}

FrictionLog load_friction_log(const fs::path& file, const RawFrictionOptions& raw) {
  return load_friction_logs({file}, raw);
}

FrictionLog load_friction_logs(const std::vector<fs::path>& files, const RawFrictionOptions& raw) {
  std::vector<detail::FrictionFile> list;
  for (const fs::path& file : files) list.push_back({.path = file});
  return detail::load_friction_files(list, raw);
}

namespace detail {

namespace {

// Thrown where files read apart bear on each other (read_files_apart): the files are then read
// one after the other, which says what and where.
struct FilesDisagree : std::exception {
  const char* what() const noexcept override { return "the files of a log read apart disagree"; }
};

// `part`, one file read into a log of its own, appended to `log` as reading it after the files
// before would have: its run and guide names mapped to the log's in the order they first
// appear, its report, runs' segmentation and traces after the others'. Where that reading
// would have refused the file (what it gives of the law's conditions differs; the limit on
// names), FilesDisagree.
void append_file(FrictionLog& log, NameIndex& runs, NameIndex& guides, const FrictionLog& part) {
  const std::vector<std::uint32_t> run_map = map_names<FilesDisagree>(runs, part.run_names);
  const std::vector<std::uint32_t> guide_map = map_names<FilesDisagree>(guides, part.guide_names);
  FrictionLawConditions& law = log.law;
  if (log.reports.empty()) {
    law = part.law;
  } else {
    const FrictionLawConditions& given = part.law;
    if (law.load != given.load || law.preload != given.preload || law.block_length != given.block_length ||
        law.temperature != given.temperature)
      throw FilesDisagree();
    for (std::optional<double> FrictionLawConditions::*stated :
         {&FrictionLawConditions::load_N, &FrictionLawConditions::preload_um, &FrictionLawConditions::block_length_mm,
          &FrictionLawConditions::preload_N}) {
      if (!(given.*stated)) continue;
      if (!(law.*stated)) law.*stated = given.*stated;
      if (*(law.*stated) != *(given.*stated)) throw FilesDisagree();
    }
    if (!law.preload_class) law.preload_class = given.preload_class;
  }
  const auto append = [](auto& to, const auto& more) { to.insert(to.end(), more.begin(), more.end()); };
  for (std::uint32_t r : part.run) log.run.push_back(run_map[r]);
  for (std::uint32_t g : part.guide) log.guide.push_back(guide_map[g]);
  append(log.time_s, part.time_s);
  append(log.velocity_m_s, part.velocity_m_s);
  append(log.load_N, part.load_N);
  append(log.preload_um, part.preload_um);
  append(log.block_length_mm, part.block_length_mm);
  append(log.temperature_C, part.temperature_C);
  append(log.friction_N, part.friction_N);
  append(log.viscosity40_mm2_s, part.viscosity40_mm2_s);
  append(log.direction, part.direction);
  append(log.acceleration_m_s2, part.acceleration_m_s2);
  append(log.position_m, part.position_m);
  append(log.distance_since_reversal_m, part.distance_since_reversal_m);
  append(log.time_since_reversal_s, part.time_since_reversal_s);
  append(log.line, part.line);
  append(log.reports, part.reports);
  append(log.segmentation, part.segmentation);
  append(log.raw_traces, part.raw_traces);
  if (part.trajectory) {
    log.trajectory = true;
    log.axis_incline_deg = part.axis_incline_deg;
  }
}

// Several files, each read (parsed, and a raw file's runs segmented) on a free thread into a log
// of its own, then appended in file order (append_file): the log reading them one after the
// other gives, the same bits. A 10⁶-sample trajectory in three raw files loaded in 2/3 of the
// time on two cores. Null where it cannot decide (a file refused, files that bear on each
// other): the caller reads them one after the other.
std::optional<FrictionLog> read_files_apart(const std::vector<FrictionFile>& files, const RawFrictionOptions& raw) {
  std::vector<FrictionLog> parts(files.size());
  try {
    for_each_index(files.size(), [&](std::size_t k) {
      NameIndex runs(parts[k].run_names), guides(parts[k].guide_names);
      FileLoader(files[k], raw, parts[k], runs, guides).load(nullptr);
    });
  } catch (const std::exception&) {
    return std::nullopt;
  }
  FrictionLog log;
  log.force_sensor = raw.force_sensor;
  log.incline_stated = raw.incline_stated;
  std::size_t total = 0;
  for (const FrictionLog& part : parts) total += part.size();
  FileLoader::reserve(log, total);
  NameIndex runs(log.run_names), guides(log.guide_names);
  try {
    for (const FrictionLog& part : parts) append_file(log, runs, guides, part);
  } catch (const FilesDisagree&) {
    return std::nullopt;
  }
  return log;
}

}  // namespace

FrictionLog load_friction_files(const std::vector<FrictionFile>& files, const RawFrictionOptions& raw) {
  raw.validate();
  if (files.size() >= 2 && slice_threads(files.size(), 1) > 1)
    if (std::optional<FrictionLog> log = read_files_apart(files, raw)) return std::move(*log);
  const auto read = [&](bool* sliced) {
    FrictionLog log;
    log.force_sensor = raw.force_sensor;
    log.incline_stated = raw.incline_stated;
    NameIndex runs(log.run_names);
    NameIndex guides(log.guide_names);
    for (const FrictionFile& file : files) FileLoader(file, raw, log, runs, guides).load(sliced);
    return log;
  };
  // Large files are read in slices in parallel; when that throws (a bad row, slices that
  // disagree), the files are read again line by line, which says what and where as it always did.
  bool sliced = false;
  try {
    return read(&sliced);
  } catch (const std::exception&) {
    if (!sliced) throw;
  }
  return read(nullptr);
}

}  // namespace detail

std::string friction_log_csv(const FrictionLog& log, const std::vector<std::string>& comments) {
  // Optional columns are written when they carry information: guide when a sample names
  // one, time when every sample has one (a NaN time would not load back).
  const bool with_guide =
      std::any_of(log.guide_names.begin(), log.guide_names.end(), [](const std::string& g) { return !g.empty(); });
  const bool with_time =
      log.size() != 0 && std::none_of(log.time_s.begin(), log.time_s.end(), [](double t) { return std::isnan(t); });
  // The acceleration when a sample has one (a moving mass's error shows against it).
  const bool with_acceleration =
      std::any_of(log.acceleration_m_s2.begin(), log.acceleration_m_s2.end(), [](double a) { return a != 0; });

  std::vector<std::string> header{header_of(kRun)};
  if (with_guide) header.push_back(header_of(kGuide));
  if (with_time) header.push_back(header_of(kTime));
  for (Spec spec : {kVelocity, kLoad, kPreload, kBlockLength, kTemperature, kFriction, kViscosity40, kDirection}) {
    header.push_back(header_of(spec));
  }
  if (with_acceleration) header.push_back(header_of(kAcceleration));

  CsvText csv(header, comments);
  for (std::size_t i = 0; i < log.size(); ++i) {
    csv.cell(log.run_names.at(log.run[i]));
    if (with_guide) csv.cell(log.guide_names.at(log.guide[i]));
    if (with_time) csv.cell(log.time_s[i]);
    csv.cell(log.velocity_m_s[i])
        .cell(log.load_N[i])
        .cell(log.preload_um[i])
        .cell(log.block_length_mm[i])
        .cell(log.temperature_C[i])
        .cell(log.friction_N[i])
        .cell(log.viscosity40_mm2_s[i])
        .cell(static_cast<double>(log.direction[i]));
    if (with_acceleration) csv.cell(log.acceleration_m_s2[i]);
    csv.end_row();
  }
  return csv.str();
}

}  // namespace lmcal

