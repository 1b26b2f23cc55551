#include "calibrate/data_checks.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>

namespace lmcal::detail {

namespace {

double median(std::vector<double> v) {
  std::erase_if(v, [](double x) { return !std::isfinite(x); });
  if (v.empty()) return std::nan("");
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  if (v.size() % 2 == 1) return *mid;
  return (*mid + *std::max_element(v.begin(), mid)) / 2;
}

void load_warnings(const std::vector<LoadReport>& reports, std::vector<std::string>& out) {
  for (const auto& r : reports)
    for (const auto& w : r.warnings) out.push_back(fmt::format("{}: {}", r.file, w));
}

// Friction runs whose residuals (measured − the fitted law, each run's zero included) are far
// larger than the typical run's: a run logged with another setup, load or unit than stated.
void friction_run_warnings(const Calibration& c, std::vector<std::string>& out) {
  if (!c.friction || !c.friction_log) return;
  const FrictionLog& log = *c.friction_log;
  const FrictionFitResult& f = *c.friction;
  const std::size_t runs = log.run_names.size();
  if (runs < 3 || f.predicted_N.size() != log.size()) return;
  std::vector<double> ss(runs, 0.0), n(runs, 0.0);
  for (std::size_t i = 0; i < log.size(); ++i) {
    const double r = log.friction_N[i] - f.predicted_N[i];
    ss[log.run[i]] += r * r;
    n[log.run[i]] += 1;
  }
  std::vector<double> rms(runs);
  for (std::size_t r = 0; r < runs; ++r) rms[r] = n[r] > 0 ? std::sqrt(ss[r] / n[r]) : std::nan("");
  const double typical = median(rms);
  if (!(typical > 0)) return;
  for (std::size_t r = 0; r < runs; ++r) {
    if (rms[r] > kRunRmsRatio * typical) {
      out.push_back(fmt::format("friction run '{}' disagrees with the others: its residual RMS is {:.3g} N, {:.1f} times the "
                                "median run's {:.3g} N (another setup, load, unit or sign than stated?)",
                                log.run_names[r], rms[r], rms[r] / typical, typical));
    }
  }
}

void thermal_run_warnings(const Calibration& c, std::vector<std::string>& out) {
  if (!c.thermal) return;
  const ThermalFitResult& t = *c.thermal;
  std::vector<std::string> paper_heat;
  for (const auto& run : t.runs)
    if (run.heat_source.find("paper's constants") != std::string::npos) paper_heat.push_back(run.id);
  if (!paper_heat.empty()) {
    out.push_back(fmt::format("thermal run{} {}: the heat came from the paper's friction constants, because nothing else was "
                              "given; α is then only as right as those constants are for this rig. Give friction logs "
                              "(friction*.csv), the measured friction (mean_friction_N) or the heater's power (heat_rate_W)",
                              paper_heat.size() > 1 ? "s" : "", fmt::join(paper_heat, ", ")));
  }
  if (t.per_run.size() < 3 || t.per_run.size() != t.runs.size()) return;
  std::vector<double> alpha, se;
  for (const auto& fit : t.per_run) {
    const auto it = std::find_if(fit.parameters.begin(), fit.parameters.end(), [](const auto& p) { return p.name == "alpha"; });
    alpha.push_back(it == fit.parameters.end() ? std::nan("") : it->value);
    se.push_back(it == fit.parameters.end() ? std::nan("") : it->se);
  }
  const double centre = median(alpha);
  std::vector<double> deviation;
  for (double a : alpha) deviation.push_back(std::abs(a - centre));
  const double sigma = std::max(1.4826 * median(deviation), median(se));
  if (!(sigma > 0)) return;
  for (std::size_t r = 0; r < alpha.size(); ++r) {
    const double z = (alpha[r] - centre) / sigma;
    if (std::abs(z) > kRunOutlierZ) {
      out.push_back(fmt::format("thermal run '{}' disagrees with the others: its own α {:.3f} is {:.1f} robust σ from the runs' "
                                "median {:.3f} (another heat, sensor position or guide than stated?)",
                                t.runs[r].id, alpha[r], z, centre));
    }
  }
}

}  // namespace

std::vector<std::string> calibration_warnings(const Calibration& c) {
  std::vector<std::string> out;
  if (c.friction_log) load_warnings(c.friction_log->reports, out);
  if (c.thermal_data) {
    std::vector<LoadReport> reports;
    for (const auto& run : c.thermal_data->runs) reports.push_back(run.trace.report);
    load_warnings(reports, out);
  }
  friction_run_warnings(c, out);
  thermal_run_warnings(c, out);
  // The calibrated models' own warnings (a parameter on its bound, a fit that stopped short):
  // the summary's parameter lines are theirs, so are these.
  const CalibratedModel& m = c.calibrated;
  if (m.friction)
    for (const std::string& w : m.friction->fit.warnings) out.push_back("the calibrated friction model: " + w);
  if (m.thermal)
    for (const std::string& w : m.thermal->joint.warnings) out.push_back("the calibrated rail model: " + w);
  return out;
}

}  // namespace lmcal::detail
