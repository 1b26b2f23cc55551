// read_friction_fit (how `lmcal fit thermal --friction FILE` and the calibration read a friction
// fit JSON) on fuzzed JSON: refused with an InputError naming the file, or read with finite
// constants and effects and a finite covariance (NaN only as a standard error that was not
// estimated). JSON errors carry no line (the reader gives the byte offset as the column), so
// only the file is required. The JSON writer needs a whole fit, so there is no round trip.
#include "fuzz_support.hpp"

#include "lmcal/fit/thermal_fit.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace lmcal::fuzz;
  const fs::path file = write_file("friction.json", as_text(data, size));
  lmcal::ThermalFitOptions options;
  const auto read = loaded_or_refused(
      [&] {
        lmcal::read_friction_fit(file.string(), options);
        return true;
      },
      {file}, false);
  if (!read) return 0;
  if (!options.friction || !options.friction_fit) finding("read_friction_fit returned without constants or their fit");
  const lmcal::FrictionConstants<double>& k = *options.friction;
  for (const double v : {k.k1, k.k2, k.mu_st, k.v_st_m_s, k.mu_v, k.beta_per_K, k.f0, k.nu_ref_mm2_s, k.T_ref_C})
    finite(v, "friction constant");
  for (const double v : options.friction_effects.values) finite(v, "friction effect");
  for (const lmcal::ParameterEstimate& p : options.friction_fit->parameters) {
    if (!std::isnan(p.value)) finite(p.value, p.name + " value");  // NaN: null in the file (not estimated)
    if (!std::isnan(p.se)) finite(p.se, p.name + " se");
  }
  const auto& covariance = options.friction_fit->covariance;
  for (Eigen::Index i = 0; i < covariance.size(); ++i) finite(covariance.data()[i], "covariance");
  return 0;
}
