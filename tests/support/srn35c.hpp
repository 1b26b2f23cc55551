// The paper's SRN 35C rail case (Tables 2-3) as test inputs. The rail length is not
// reported by the paper; 0.6 m is an assumed value used throughout the tests.
#pragma once

#include "lmcal/models/friction.hpp"
#include "lmcal/models/rail_thermal.hpp"

namespace lmcal::test {

inline RailGeometry srn35c_geometry(double velocity_m_s = 0.11) {
  return {.rail_length_m = 0.6, .area_m2 = 8.88e-4, .perimeter_m = 0.14, .stroke_m = 0.2,
          .contact_length_m = 0.0822, .velocity_m_s = velocity_m_s};
}

inline FrictionConditions<double> srn35c_conditions(double velocity_m_s = 0.11) {
  return {.load_N = 3000, .preload_um = 4, .block_length_mm = 120.2, .velocity_m_s = velocity_m_s,
          .temperature_C = 26};
}

inline RailParams<double> srn35c_params(double heat_rate_W = 4.86) {
  return {.heat_partition = 0.6, .heat_rate_W = heat_rate_W, .h_W_m2K = 5.3, .conductivity_W_mK = 18,
          .density_kg_m3 = 7800, .specific_heat_J_kgK = 461, .initial_temperature_C = 26};
}

}  // namespace lmcal::test
