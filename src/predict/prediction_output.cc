// `lmcal predict`'s outputs: a prediction summarized (its end, its largest elongation, each
// segment's end) and written as prediction.json, prediction_time.csv and the terminal summary
// (prediction.hpp); predict() in prediction.cc makes it.

#include "lmcal/version.hpp"
#include "lmcal/predict/prediction.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "lmcal/error.hpp"
#include "lmcal/io/csv_writer.hpp"

namespace lmcal {

PredictionSummary summarize(const Prediction& p) {
  LMCAL_ASSERT(!p.time_s.empty() && p.segment.size() == p.time_s.size(), "a prediction with outputs");
  const auto at = [](const Band& b, std::size_t t) { return BandAt{b.value[t], b.low[t], b.high[t]}; };
  const auto moment = [&](std::size_t t) {
    PredictionMoment m{p.segment[t], t, p.time_s[t], at(p.elongation_um, t), {}, {}};
    for (const Band& b : p.temperature_C) m.temperature_C.push_back(at(b, t));
    for (const Band& b : p.scale_error_um) m.scale_error_um.push_back(at(b, t));
    return m;
  };
  const std::size_t end = p.time_s.size() - 1;
  std::size_t largest = 0;
  for (std::size_t t = 0; t <= end; ++t)
    if (std::abs(p.elongation_um.value[t]) > std::abs(p.elongation_um.value[largest])) largest = t;
  PredictionSummary s{moment(end), moment(largest), {}};
  for (std::size_t t = 0; t <= end; ++t)
    if (t == end || p.segment[t + 1] != p.segment[t]) s.segment_ends.push_back(moment(t));
  return s;
}

namespace {

nlohmann::json band_json(const Band& b) { return {{"value", b.value}, {"low", b.low}, {"high", b.high}}; }
nlohmann::json band_at_json(const BandAt& b) { return {{"value", b.value}, {"low", b.low}, {"high", b.high}}; }

nlohmann::json moment_json(const PredictionMoment& m, const Prediction& p) {
  nlohmann::json temperatures = nlohmann::json::array(), scale = nlohmann::json::array();
  for (std::size_t q = 0; q < m.temperature_C.size(); ++q)
    temperatures.push_back({{"position_m", p.positions_m[q]}, {"band", band_at_json(m.temperature_C[q])}});
  for (std::size_t q = 0; q < m.scale_error_um.size(); ++q)
    scale.push_back({{"position_m", p.scale_positions_m[q]}, {"band", band_at_json(m.scale_error_um[q])}});
  return {{"segment", m.segment}, {"time_s", m.time_s}, {"elongation_um", band_at_json(m.elongation_um)},
          {"temperature_C", temperatures}, {"scale_error_um", scale}};
}

}  // namespace

std::string prediction_json(const Prediction& p, const DutyCycle& duty, const ModelFile& model,
                            const std::vector<std::string>& command) {
  nlohmann::json segments = nlohmann::json::array();
  for (const auto& s : duty.segments)
    segments.push_back({{"name", s.name}, {"duration_s", s.duration_s}, {"velocity_m_s", s.velocity_m_s}, {"load_N", s.load_N},
                        {"stroke_m", s.stroke_m}, {"preload_um", s.preload_um}, {"block_length_mm", s.block_length_mm},
                        {"viscosity40_mm2_s", s.viscosity40_mm2_s}});
  nlohmann::json outside = nlohmann::json::array();
  for (const auto& f : p.outside)
    outside.push_back({{"segment", f.segment}, {"quantity", f.quantity}, {"value", f.value}, {"calibrated", {f.low, f.high}},
                       {"calibration", f.what}});
  const PredictionSummary summary = summarize(p);
  nlohmann::json ends = nlohmann::json::array();
  for (const auto& m : summary.segment_ends) ends.push_back(moment_json(m, p));
  const nlohmann::json j = {
      {"kind", "prediction"},
      {"lmcal_version", LMCAL_VERSION}, {"schema_version", kOutputSchemaVersion},
      {"command", command},
      {"model", {{"set", model.set}, {"guide", model.guide}, {"lmcal_version", model.lmcal_version}, {"command", model.command}}},
      {"duty",
       {{"file", duty.file},
        {"guide", duty.guide.model},
        {"rail_length_m", duty.rail_length_m},
        {"duration_s", duty.duration_s()},
        {"segments", segments},
        {"scale",
         {{"from_m", duty.scale.from_m},
          {"to_m", duty.scale.to_m},
          {"mounting", duty.scale.mounting == ScaleMounting::end ? "end" : "centre"},
          {"fixed_point_m", duty.scale.fixed_point_m()},
          {"expansion_per_K", duty.scale.expansion_per_K}}}}},
      {"band", {{"method", p.method}, {"draws", p.samples}, {"notes", p.notes}}},
      {"outside_calibrated_range", outside},
      {"positions_m", p.positions_m},
      {"scale_positions_m", p.scale_positions_m},
      {"end", moment_json(summary.end, p)},
      {"largest_elongation", moment_json(summary.largest, p)},
      {"segment_ends", ends},
      {"series",
       {{"file", "prediction_time.csv"},
        {"what", "every output time's value and band of each quantity, one row per time, quantity and position"},
        {"columns", {"time_s", "segment", "quantity", "position_m", "value", "low", "high"}},
        {"quantities", {"temperature_C", "elongation_um", "scale_error_um", "friction_N", "heat_rate_W"}},
        {"outputs", p.time_s.size()},
        {"from_s", p.time_s.front()},
        {"to_s", p.time_s.back()}}},
      {"end_profile", {{"x_m", p.profile_x_m}, {"temperature_C", band_json(p.profile_C)}}}};
  return j.dump(1) + "\n";
}

std::string prediction_time_csv(const Prediction& p) {
  CsvText csv({"time_s", "segment", "quantity", "position_m", "value", "low", "high"});
  const auto rows = [&](const char* quantity, std::optional<double> position, const Band& b) {
    for (std::size_t t = 0; t < p.time_s.size(); ++t) {
      csv.cell(p.time_s[t]).cell(p.segment[t]).cell(quantity);
      if (position) csv.cell(*position);
      else csv.cell("");
      csv.cell(b.value[t]).cell(b.low[t]).cell(b.high[t]).end_row();
    }
  };
  for (std::size_t q = 0; q < p.positions_m.size(); ++q) rows("temperature_C", p.positions_m[q], p.temperature_C[q]);
  rows("elongation_um", std::nullopt, p.elongation_um);
  for (std::size_t q = 0; q < p.scale_positions_m.size(); ++q) rows("scale_error_um", p.scale_positions_m[q], p.scale_error_um[q]);
  rows("friction_N", std::nullopt, p.friction_N);
  rows("heat_rate_W", std::nullopt, p.heat_rate_W);
  return csv.str();
}

std::string prediction_summary(const Prediction& p) {
  const PredictionSummary s = summarize(p);
  const auto band = [](const BandAt& b) { return fmt::format("{:.4g} [{:.4g}, {:.4g}]", b.value, b.low, b.high); };
  std::string out = fmt::format("prediction over {:.4g} h, {} draws (95 % bands):\n", p.time_s.back() / 3600, p.samples);
  for (std::size_t q = 0; q < p.positions_m.size(); ++q)
    out += fmt::format("  rail at x = {} m at the end: {} °C\n", p.positions_m[q], band(s.end.temperature_C[q]));
  out += fmt::format("  rail elongation at the end: {} µm; largest {} µm at {:.4g} h\n", band(s.end.elongation_um),
                     band(s.largest.elongation_um), s.largest.time_s / 3600);
  for (std::size_t q = 0; q < p.scale_positions_m.size(); ++q)
    out += fmt::format("  scale error at x = {} m at the end: {} µm\n", p.scale_positions_m[q], band(s.end.scale_error_um[q]));
  // Each segment's last output time (a shift's end, a night's): where a machine is measured.
  out += "  at the end of each segment: rail elongation, µm";
  if (!p.positions_m.empty()) out += fmt::format("; rail at x = {} m, °C", p.positions_m.front());
  out += "\n";
  constexpr std::size_t kShownEnds = 12;  // a repeated duty's: the first ones (all in prediction.json)
  for (std::size_t k = 0; k < std::min(kShownEnds, s.segment_ends.size()); ++k) {
    const PredictionMoment& m = s.segment_ends[k];
    out += fmt::format("    {:<24} {:>7.4g} h  {}", m.segment, m.time_s / 3600, band(m.elongation_um));
    if (!m.temperature_C.empty()) out += "  " + band(m.temperature_C.front());
    out += "\n";
  }
  if (s.segment_ends.size() > kShownEnds)
    out += fmt::format("    … {} more segment ends (all in prediction.json and prediction.html)\n", s.segment_ends.size() - kShownEnds);
  for (const auto& f : p.outside)
    out += fmt::format("  outside the calibrated range: {} {} = {:.4g} ({} calibration: [{:.4g}, {:.4g}])\n", f.segment,
                       f.quantity, f.value, f.what, f.low, f.high);
  return out;
}

}  // namespace lmcal
