#include "lmcal/models/friction.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <string>
#include <vector>

#include "lmcal/error.hpp"
#include "lmcal/io/units.hpp"
#include "lmcal/models/friction_effects.hpp"

namespace lmcal {

void validate(const FrictionConstants<double>& k) {
  require_finite("k1", k.k1);
  require_finite("k2", k.k2);
  require_non_negative("mu_st", k.mu_st);
  require_positive("v_st_m_s", k.v_st_m_s);
  require_non_negative("mu_v", k.mu_v);
  require_finite("beta_per_K", k.beta_per_K);
  require_finite("f0", k.f0);
  require_positive("nu_ref_mm2_s", k.nu_ref_mm2_s);
  require_in_range("T_ref_C", k.T_ref_C, -273.15, 1000.0);
}

// The signs are the law's (a speed, a load); the upper ends are the loaders' ranges of a rig's
// values (units.hpp physical_range), beyond which the law's terms leave the doubles: a speed of
// 1e308 m/s makes the viscous term inf and the total NaN.
void validate(const FrictionConditions<double>& c) {
  require_in_range("load_N", c.load_N, 0.0, physical_range(Quantity::force).high);
  require_in_range("preload_um", c.preload_um, 0.0, physical_range(Quantity::preload).high);
  require_positive("block_length_mm", c.block_length_mm);
  require_in_range("block_length_mm", c.block_length_mm, 0.0, physical_range(Quantity::length_mm).high);
  require_in_range("velocity_m_s", c.velocity_m_s, 0.0, physical_range(Quantity::velocity).high);
  require_in_range("temperature_C", c.temperature_C, -273.15, physical_range(Quantity::temperature).high);
}

}  // namespace lmcal

namespace lmcal {

std::size_t friction_constant_index(const std::string& parameter, std::string_view name) {
  if (const auto j = find_friction_constant(name)) return *j;
  throw InvalidParameter(parameter, "unknown constant '" + std::string(name) +
                                        "'; expected one of k1, k2, mu_st, v_st_m_s, mu_v, beta_per_K, f0");
}

void with_effect_parts(std::vector<std::string>& names, std::vector<double>* starts) {
  const auto& infos = FrictionEffectLibrary::infos;
  const auto given = [&](std::string_view name) { return std::find(names.begin(), names.end(), name) != names.end(); };
  std::vector<std::string> out;
  std::vector<double> out_starts;
  for (std::size_t m = 0; m < names.size(); ++m) {
    const bool started = starts != nullptr && m < starts->size();
    out.push_back(names[m]);
    if (started) out_starts.push_back((*starts)[m]);
    const auto slot = find_friction_effect(names[m]);
    if (!slot) continue;
    if (is_friction_effect_part(infos[*slot])) {
      if (!given(infos[*slot].part_of))
        throw InvalidParameter("effect", fmt::format("'{}' is a shape parameter of {}: fit it with {}", names[m],
                                                     infos[*slot].part_of, infos[*slot].part_of));
      continue;
    }
    for (std::size_t p = *slot + 1; p < kFrictionEffectCount && infos[p].part_of == std::string_view(names[m]); ++p) {
      if (given(infos[p].name)) continue;  // given: keeps its place and its start
      out.push_back(infos[p].name);
      if (started) out_starts.push_back(infos[p].neutral);
    }
  }
  names = std::move(out);
  if (starts != nullptr) *starts = std::move(out_starts);
}

std::size_t friction_effect_slot(std::string_view name) {
  if (const auto slot = find_friction_effect(name)) return *slot;
  std::string known;
  for (const auto& info : FrictionEffectLibrary::infos) known += (known.empty() ? "" : ", ") + std::string(info.name);
  throw InvalidParameter("effect", "unknown friction effect '" + std::string(name) + "'; known: " + known);
}

}  // namespace lmcal
