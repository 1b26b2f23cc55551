// A thermal run's trace: its CSV read (load_thermal_trace) and written (thermal_trace_csv); the
// manifest that names the runs is thermal_manifest.cc.
#include "lmcal/io/thermal_run.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "io/csv_reader.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/csv_writer.hpp"
#include "lmcal/io/units.hpp"

namespace lmcal {

namespace {

namespace fs = std::filesystem;

// ---- Trace CSV ----------------------------------------------------------------------------

// Ambient columns are optional here: a manifest run without them gives ambient_C instead.
enum TraceSpec : std::size_t { kTime, kAmbient, kRail, kHeatColumn };
constexpr std::array<csv::ColumnSpec, 4> kTraceSpecs{{
    {.name = "time", .quantity = Quantity::time, .required = true},
    {.name = "ambient",
     .quantity = Quantity::temperature,
     .family = true,
     .rule = csv::Rule::above_absolute_zero},
    {.name = "tc",
     .quantity = Quantity::temperature,
     .required = true,
     .family = true,
     .rule = csv::Rule::above_absolute_zero},
    {.name = "heat_rate_W", .rule = csv::Rule::non_negative, .hint = "a heat rate is >= 0", .range = kHeatRateRange},
}};

// A gap is an interval longer than 1.5x the median interval (the logger's step).
constexpr double kGapFactor = 1.5;

std::size_t count_time_gaps(const std::vector<double>& time_s) {
  if (time_s.size() < 3) return 0;
  std::vector<double> steps(time_s.size() - 1);
  for (std::size_t i = 0; i + 1 < time_s.size(); ++i) steps[i] = time_s[i + 1] - time_s[i];
  const auto middle = steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2);
  std::nth_element(steps.begin(), middle, steps.end());  // reorders: the count below uses time_s
  double median = *middle;
  if (steps.size() % 2 == 0) median = 0.5 * (median + *std::max_element(steps.begin(), middle));
  std::size_t gaps = 0;
  for (std::size_t i = 0; i + 1 < time_s.size(); ++i) gaps += time_s[i + 1] - time_s[i] > kGapFactor * median;
  return gaps;
}

// "tc1_K" -> "tc1_C": the header a channel gets in canonical units.
std::string canonical_channel(const std::string& name) {
  const auto split = split_unit(name, Quantity::temperature);
  return csv::canonical_name(split ? split->name : name, Quantity::temperature);
}

}  // namespace

ThermalTrace load_thermal_trace(const fs::path& file, std::size_t skip_lines) {
  csv::Reader reader(file, skip_lines);
  ThermalTrace trace;
  LoadReport& report = trace.report;
  report.file = reader.file();
  reader.read_header();
  const std::vector<csv::Column> columns = csv::bind_header(reader, kTraceSpecs, report);
  const csv::Column& time = *csv::find_column(columns, kTime);
  const csv::Column* heat = csv::find_column(columns, kHeatColumn);

  // Channels in header order, ambient and rail apart.
  std::vector<const csv::Column*> channel_columns;
  for (const csv::Column& c : columns) {
    if (c.spec == kTime || c.spec == kHeatColumn) continue;
    (c.spec == kAmbient ? trace.ambient : trace.rail).push_back({c.header, {}});
    channel_columns.push_back(&c);
  }
  struct Channel {
    const csv::Column* column;
    std::vector<double>* values;
    std::size_t missing = 0;
  };
  std::vector<Channel> channels;
  std::size_t ambient = 0, rail = 0;
  for (const csv::Column* c : channel_columns) {
    channels.push_back({c, c->spec == kAmbient ? &trace.ambient[ambient++].values : &trace.rail[rail++].values});
  }

  const std::size_t rows = reader.estimated_rows();
  trace.time_s.reserve(rows);
  trace.line.reserve(rows);
  for (Channel& c : channels) c.values->reserve(rows);

  long previous_line = 0;
  while (reader.next()) {
    const double t = reader.number(time, false);
    if (!trace.time_s.empty() && !(t > trace.time_s.back())) {
      reader.fail(time.cell, fmt::format("{} = {} is not later than the previous row's (line {}); time must "
                                         "increase strictly",
                                         time.header, reader.cell(time.cell), previous_line));
    }
    if (!trace.time_s.empty() && t - trace.time_s.front() > kMaxRunSpan_s)
      reader.fail(time.cell, fmt::format("{} = {}: the run would span {:.3g} s; a run may span at most {:.0e} s (about {:.0f} "
                                         "days)",
                                         time.header, reader.cell(time.cell), t - trace.time_s.front(), kMaxRunSpan_s,
                                         kMaxRunSpan_s / 86400));
    trace.time_s.push_back(t);
    // A measured power has no gaps to skip: the heat between records must be known.
    if (heat) trace.heat_rate_W.push_back(reader.number(*heat, false));
    previous_line = reader.line();
    trace.line.push_back(static_cast<std::uint32_t>(previous_line));
    for (Channel& c : channels) {
      const double value = reader.number(*c.column, true);
      c.missing += std::isnan(value);
      c.values->push_back(value);
    }
  }
  if (trace.time_s.empty()) reader.fail_at(reader.header_line(), 0, "no data rows below the header");

  report.rows_read = report.rows_kept = trace.time_s.size();
  for (const Channel& c : channels) {
    if (c.missing != 0) report.missing[c.column->header] = c.missing;
  }
  report.time_gaps = count_time_gaps(trace.time_s);
  report.bytes = static_cast<double>(reader.bytes());
  return trace;
}

std::string thermal_trace_csv(const ThermalTrace& trace, const std::vector<std::string>& comments) {
  std::vector<std::string> header{csv::canonical_name("time", Quantity::time)};
  std::vector<const std::vector<double>*> columns;
  for (const auto* group : {&trace.ambient, &trace.rail}) {
    for (const TemperatureChannel& channel : *group) {
      LMCAL_ASSERT(channel.values.size() == trace.size(), "temperature channel length differs from time_s");
      header.push_back(canonical_channel(channel.name));
      columns.push_back(&channel.values);
    }
  }
  const bool heat = !trace.heat_rate_W.empty();
  LMCAL_ASSERT(!heat || trace.heat_rate_W.size() == trace.size(), "heat_rate_W length differs from time_s");
  if (heat) header.emplace_back(kTraceSpecs[kHeatColumn].name);
  CsvText csv(header, comments);
  for (std::size_t i = 0; i < trace.size(); ++i) {
    csv.cell(trace.time_s[i]);
    for (const auto* values : columns) csv.cell((*values)[i]);
    if (heat) csv.cell(trace.heat_rate_W[i]);
    csv.end_row();
  }
  return csv.str();
}

}  // namespace lmcal
