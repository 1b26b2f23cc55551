// Fits the seven friction constants to a friction log and prints each with its 95 % interval.
#include <cstdio>
#include <exception>

#include "lmcal/fit/friction_fit.hpp"
#include "lmcal/io/friction_log.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fit_log FRICTION_LOG.csv\n");
    return 2;
  }
  try {
    const lmcal::FrictionLog log = lmcal::load_friction_log(argv[1]);
    const lmcal::FrictionFitResult fit = lmcal::fit_friction(log, lmcal::FrictionFitOptions{});
    for (const auto& p : fit.fit.parameters)
      std::printf("%-12s %12.6g  [%.6g, %.6g]  %s\n", p.name.c_str(), p.value, p.ci_low, p.ci_high, p.unit.c_str());
    std::printf("rmse_N %.6g over %zu samples\n", fit.rmse_N, log.size());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
