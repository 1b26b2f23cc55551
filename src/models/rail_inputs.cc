// The rail model's inputs (rail_thermal.hpp): the time schemes' names, the ambient trace read
// at a time, a guide's geometry and material from the catalog, and their checks.
#include <fmt/format.h>

#include <algorithm>
#include <string>

#include "lmcal/error.hpp"
#include "lmcal/io/limits.hpp"
#include "lmcal/models/rail_thermal.hpp"

namespace LMCAL_API lmcal {

std::string_view to_string(TimeScheme scheme) {
  return scheme == TimeScheme::backward_euler ? "backward-euler" : "crank-nicolson";
}

TimeScheme parse_time_scheme(std::string_view name) {
  if (name == "backward-euler" || name == "be") return TimeScheme::backward_euler;
  if (name == "crank-nicolson" || name == "cn") return TimeScheme::crank_nicolson;
  throw InvalidParameter("scheme", "unknown time scheme '" + std::string(name) +
                                       "'; expected backward-euler (be) or crank-nicolson (cn)");
}

double AmbientTrace::at(double t) const {
  std::size_t place = 1;
  return at(t, place);
}

double AmbientTrace::at(double t, std::size_t& j) const {
  LMCAL_ASSERT(!time_s.empty() && time_s.size() == temperature_C.size(), "ambient trace is empty or ragged");
  if (time_s.size() == 1 || t <= time_s.front()) return temperature_C.front();
  if (t >= time_s.back()) return temperature_C.back();
  // j: the first sample after t (upper_bound's), 1 <= j < size. A time loop reads nearby times,
  // forward and back: walk a few samples from where the last read ended, bisect beyond that.
  // (front < t < back here, so a walk never leaves [1, size - 1].)
  const auto before_t = [&](std::size_t k) { return time_s[k] <= t; };
  j = std::clamp<std::size_t>(j, 1, time_s.size() - 1);
  for (int walk = 0; walk < 8 && (before_t(j) || !before_t(j - 1)); ++walk) before_t(j) ? ++j : --j;
  if (before_t(j) || !before_t(j - 1))
    j = static_cast<std::size_t>(std::upper_bound(time_s.begin(), time_s.end(), t) - time_s.begin());
  const double s = (t - time_s[j - 1]) / (time_s[j] - time_s[j - 1]);
  return temperature_C[j - 1] + s * (temperature_C[j] - temperature_C[j - 1]);
}

void validate(const RailGeometry& g) {
  require_positive("rail_length_m", g.rail_length_m);
  require_positive("area_m2", g.area_m2);
  require_positive("perimeter_m", g.perimeter_m);
  require_positive("stroke_m", g.stroke_m);
  require_positive("contact_length_m", g.contact_length_m);
  require_non_negative("velocity_m_s", g.velocity_m_s);
  if (g.stroke_m + g.contact_length_m > g.rail_length_m)
    throw InvalidParameter("rail_length_m", g.rail_length_m,
                           "at least stroke_m + contact_length_m = " +
                               std::to_string(g.stroke_m + g.contact_length_m) + " (the block must stay on the rail)");
}

void validate(const RailNumerics& n) {
  if (n.half_rail_segments < 1 || n.half_rail_segments > io::kMaxRailModelSegments)
    throw InvalidParameter("half_rail_segments", n.half_rail_segments,
                           fmt::format("from 1 to {} segments (docs/formats.md#limits)", io::kMaxRailModelSegments));
  require_positive("time_step_s", n.time_step_s);
}

RailGeometry rail_geometry_of(const GuideSpec& spec, double rail_length_m, double stroke_m, double contact_length_m,
                              double velocity_m_s) {
  return {.rail_length_m = rail_length_m,
          .area_m2 = require(spec, &GuideSpec::area_m2, "area_m2"),
          .perimeter_m = require(spec, &GuideSpec::perimeter_m, "perimeter_m"),
          .stroke_m = stroke_m,
          .contact_length_m = contact_length_m,
          .velocity_m_s = velocity_m_s};
}

RailParams<double> rail_material_of(const GuideSpec& spec) {
  RailParams<double> p;
  p.conductivity_W_mK = require(spec, &GuideSpec::conductivity_W_mK, "conductivity_W_mK");
  p.density_kg_m3 = require(spec, &GuideSpec::density_kg_m3, "density_kg_m3");
  p.specific_heat_J_kgK = require(spec, &GuideSpec::specific_heat_J_kgK, "specific_heat_J_kgK");
  return p;
}

void validate(const RailParams<double>& p) {
  require_in_range("heat_partition", p.heat_partition, 0.0, 1.0);
  require_non_negative("heat_rate_W", p.heat_rate_W);
  require_positive("h_W_m2K", p.h_W_m2K);
  require_positive("conductivity_W_mK", p.conductivity_W_mK);
  require_positive("density_kg_m3", p.density_kg_m3);
  require_positive("specific_heat_J_kgK", p.specific_heat_J_kgK);
  require_in_range("initial_temperature_C", p.initial_temperature_C, -273.15, 1000.0);
  require_non_negative("base_loss_W_mK", p.base_loss_W_mK);
  if (p.initial_profile_x_m.size() != p.initial_profile_C.size())
    throw InvalidParameter("initial_profile_C", "needs one temperature per position of initial_profile_x_m");
  for (std::size_t i = 0; i < p.initial_profile_C.size(); ++i) {
    require_in_range("initial_profile_C", p.initial_profile_C[i], -273.15, 1000.0);
    require_finite("initial_profile_x_m", p.initial_profile_x_m[i]);
    if (i > 0 && !(p.initial_profile_x_m[i] > p.initial_profile_x_m[i - 1]))
      throw InvalidParameter("initial_profile_x_m", p.initial_profile_x_m[i], "ascending positions");
  }
}

}  // namespace lmcal
