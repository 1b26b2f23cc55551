#include "lmcal/io/friction_log.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>

#include "io/csv_reader.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/csv_writer.hpp"

namespace lmcal {

namespace {

namespace fs = std::filesystem;
using csv::Rule;

constexpr double kDefaultViscosity40_mm2_s = 99.0;  // ν_i of Eq. 6 (PHYSICS.md §2)

// The columns of a friction log, in the order the writer puts them.
enum Spec : std::size_t {
  kRun,
  kGuide,
  kTime,
  kVelocity,
  kLoad,
  kPreload,
  kBlockLength,
  kTemperature,
  kFriction,
  kViscosity40,
  kDirection
};
constexpr std::array<csv::ColumnSpec, 11> kSpecs{{
    {.name = "run", .text = true, .required = true},
    {.name = "guide", .text = true},
    {.name = "time", .quantity = Quantity::time},
    {.name = "velocity",
     .quantity = Quantity::velocity,
     .required = true,
     .rule = Rule::non_negative,
     .hint = " (a speed; the direction column gives the sense)"},
    {.name = "load", .quantity = Quantity::force, .required = true, .rule = Rule::non_negative},
    {.name = "preload", .quantity = Quantity::preload, .required = true, .rule = Rule::non_negative},
    {.name = "block_length", .quantity = Quantity::length_mm, .required = true, .rule = Rule::positive},
    {.name = "temperature", .quantity = Quantity::temperature, .required = true, .rule = Rule::above_absolute_zero},
    {.name = "friction", .quantity = Quantity::force, .required = true},
    {.name = "viscosity40", .quantity = Quantity::viscosity, .rule = Rule::positive},
    {.name = "direction", .rule = Rule::plus_or_minus_one},
}};

std::string header_of(Spec spec) {
  const csv::ColumnSpec& s = kSpecs[spec];
  return s.quantity ? csv::canonical_name(s.name, *s.quantity) : std::string(s.name);
}

// Name -> index in first-appearance order, shared by all files of a log. Rows of one run
// come in blocks, so the previous name is checked before the map.
class NameIndex {
 public:
  explicit NameIndex(std::vector<std::string>& names) : names_(names) {}
  std::uint32_t operator()(std::string_view name) {
    if (last_ && name == names_[*last_]) return *last_;
    auto it = index_.find(name);
    if (it == index_.end()) {
      it = index_.emplace(std::string(name), static_cast<std::uint32_t>(names_.size())).first;
      names_.emplace_back(name);
    }
    last_ = it->second;
    return it->second;
  }

 private:
  std::vector<std::string>& names_;
  std::map<std::string, std::uint32_t, std::less<>> index_;
  std::optional<std::uint32_t> last_;
};

// The text of a run or guide cell; an empty name is an error.
std::string_view name_cell(const csv::Reader& reader, const csv::Column& column, std::string& scratch) {
  const std::string_view name = reader.text(column.cell, scratch);
  if (name.empty())
    reader.fail(column.cell, fmt::format("column '{}': expected a name, found an empty cell", column.header));
  return name;
}

// Appends the rows of one file to `log`.
void append_file(const fs::path& file, FrictionLog& log, NameIndex& runs, NameIndex& guides) {
  csv::Reader reader(file);
  LoadReport report;
  report.file = reader.file();
  reader.read_header();
  const std::vector<csv::Column> columns = csv::bind_header(reader, kSpecs, report);
  const auto column = [&](Spec spec) { return csv::find_column(columns, spec); };
  const csv::Column& run = *column(kRun);  // required columns are bound, or bind_header threw
  const csv::Column& velocity = *column(kVelocity);
  const csv::Column& load = *column(kLoad);
  const csv::Column& preload = *column(kPreload);
  const csv::Column& block_length = *column(kBlockLength);
  const csv::Column& temperature = *column(kTemperature);
  const csv::Column& friction = *column(kFriction);
  const csv::Column* guide = column(kGuide);
  const csv::Column* time = column(kTime);
  const csv::Column* viscosity40 = column(kViscosity40);
  const csv::Column* direction = column(kDirection);

  const std::size_t capacity = log.size() + reader.estimated_rows();
  for (auto* v : {&log.time_s, &log.velocity_m_s, &log.load_N, &log.preload_um, &log.block_length_mm,
                  &log.temperature_C, &log.friction_N, &log.viscosity40_mm2_s}) {
    v->reserve(capacity);
  }
  log.run.reserve(capacity);
  log.guide.reserve(capacity);
  log.direction.reserve(capacity);

  // Time must not decrease within a run (within this file): the last time and line per run.
  struct LastSample {
    double time_s = std::numeric_limits<double>::quiet_NaN();
    long line = 0;
  };
  std::vector<LastSample> last;
  std::string scratch;
  std::size_t skipped = 0;

  while (reader.next()) {
    ++report.rows_read;
    const std::uint32_t run_index = runs(name_cell(reader, run, scratch));
    const std::uint32_t guide_index = guides(guide ? name_cell(reader, *guide, scratch) : std::string_view());
    const double t = time ? reader.number(*time, false) : std::numeric_limits<double>::quiet_NaN();
    const double v = reader.number(velocity, false);
    const double p = reader.number(load, false);
    const double pc = reader.number(preload, false);
    const double lb = reader.number(block_length, false);
    const double temp = reader.number(temperature, false);
    const double f = reader.number(friction, true);
    const double nu40 = viscosity40 ? reader.number(*viscosity40, false) : kDefaultViscosity40_mm2_s;
    const double dir = direction ? reader.number(*direction, false) : 1.0;

    if (time) {
      if (last.size() <= run_index) last.resize(run_index + 1);
      LastSample& previous = last[run_index];
      if (t < previous.time_s) {
        reader.fail(time->cell,
                    fmt::format("{} = {} is earlier than the previous sample of run '{}' (line {}); time "
                                "must not decrease within a run",
                                time->header, reader.cell(time->cell), log.run_names[run_index], previous.line));
      }
      previous = {t, reader.line()};
    }
    // The rest of the row was checked: a missing friction value only skips the sample.
    if (std::isnan(f)) {
      ++skipped;
      continue;
    }
    log.append(run_index, guide_index, t,
               {.load_N = p, .preload_um = pc, .block_length_mm = lb, .velocity_m_s = v, .temperature_C = temp,
                .direction = dir},
               f, nu40);
  }
  if (report.rows_read == 0) reader.fail_at(reader.header_line(), 0, "no data rows below the header");
  if (skipped != 0) report.skipped[friction.header + " empty or NaN"] = skipped;
  report.rows_kept = report.rows_read - skipped;
  report.bytes = static_cast<double>(reader.bytes());
  log.reports.push_back(std::move(report));
}

}  // namespace

FrictionConditions<double> FrictionLog::conditions(std::size_t i) const {
  return {.load_N = load_N[i],
          .preload_um = preload_um[i],
          .block_length_mm = block_length_mm[i],
          .velocity_m_s = velocity_m_s[i],
          .temperature_C = temperature_C[i],
          .direction = static_cast<double>(direction[i])};
}

void FrictionLog::append(std::uint32_t run_index, std::uint32_t guide_index, double time,
                         const FrictionConditions<double>& c, double friction, double viscosity40) {
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
}

FrictionLog load_friction_log(const fs::path& file) { return load_friction_logs({file}); }

FrictionLog load_friction_logs(const std::vector<fs::path>& files) {
  FrictionLog log;
  NameIndex runs(log.run_names);
  NameIndex guides(log.guide_names);
  for (const fs::path& file : files) append_file(file, log, runs, guides);
  return log;
}

std::string friction_log_csv(const FrictionLog& log, const std::vector<std::string>& comments) {
  // Optional columns are written when they carry information: guide when a sample names
  // one, time when every sample has one (a NaN time would not load back).
  const bool with_guide =
      std::any_of(log.guide_names.begin(), log.guide_names.end(), [](const std::string& g) { return !g.empty(); });
  const bool with_time =
      log.size() != 0 && std::none_of(log.time_s.begin(), log.time_s.end(), [](double t) { return std::isnan(t); });

  std::vector<std::string> header{header_of(kRun)};
  if (with_guide) header.push_back(header_of(kGuide));
  if (with_time) header.push_back(header_of(kTime));
  for (Spec spec : {kVelocity, kLoad, kPreload, kBlockLength, kTemperature, kFriction, kViscosity40, kDirection}) {
    header.push_back(header_of(spec));
  }

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
        .cell(static_cast<double>(log.direction[i]))
        .end_row();
  }
  return csv.str();
}

}  // namespace lmcal
