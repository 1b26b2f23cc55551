#include "lmcal/fit/statistics.hpp"

#include <fmt/format.h>

#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <boost/math/distributions/students_t.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "lmcal/error.hpp"

namespace lmcal {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

void require_probability(double p) {
  if (!(p > 0 && p < 1)) throw InvalidParameter("probability", p, "a value in (0, 1)");
}
}  // namespace

double sample_standard_deviation(std::span<const double> values) {
  if (values.size() < 2) return kNaN;
  double mean = 0;
  for (double v : values) mean += v;
  mean /= static_cast<double>(values.size());
  double ss = 0;
  for (double v : values) ss += (v - mean) * (v - mean);
  return std::sqrt(ss / static_cast<double>(values.size() - 1));
}

double percent_difference(double e1, double e2) {
  const double mean = 0.5 * (e1 + e2);
  if (mean == 0) return kNaN;
  return std::abs(e1 - e2) / std::abs(mean) * 100.0;
}

double student_t_quantile(double probability, double dof) {
  require_probability(probability);
  require_positive("dof", dof);
  return boost::math::quantile(boost::math::students_t_distribution<double>(dof), probability);
}

double fisher_f_quantile(double probability, double d1, double d2) {
  require_probability(probability);
  require_positive("d1", d1);
  require_positive("d2", d2);
  return boost::math::quantile(boost::math::fisher_f_distribution<double>(d1, d2), probability);
}

double chi_squared_quantile(double probability, double dof) {
  require_probability(probability);
  require_positive("dof", dof);
  return boost::math::quantile(boost::math::chi_squared_distribution<double>(dof), probability);
}

double student_t_two_sided_p(double t, double dof) {
  require_positive("dof", dof);
  if (std::isnan(t)) return kNaN;
  return 2 * boost::math::cdf(boost::math::complement(boost::math::students_t_distribution<double>(dof), std::abs(t)));
}

double fisher_f_upper_p(double f, double d1, double d2) {
  require_positive("d1", d1);
  require_positive("d2", d2);
  if (std::isnan(f)) return kNaN;
  if (f <= 0) return 1.0;
  return boost::math::cdf(boost::math::complement(boost::math::fisher_f_distribution<double>(d1, d2), f));
}

double chi_squared_upper_p(double x, double dof) {
  require_positive("dof", dof);
  if (std::isnan(x)) return kNaN;
  if (x <= 0) return 1.0;
  return boost::math::cdf(boost::math::complement(boost::math::chi_squared_distribution<double>(dof), x));
}

std::string p_value_text(double p) {
  if (!std::isfinite(p)) return "n/a";
  return p < 1e-16 ? "< 1e-16" : fmt::format("{:.2g}", p);
}

std::string p_is(double p) {
  if (!std::isfinite(p)) return "p n/a";
  return p < 1e-16 ? "p < 1e-16" : fmt::format("p = {:.2g}", p);
}

std::string across_runs(const Spread& s, int digits) {
  if (s.n < 2) return s.n == 1 ? "one run: no spread across runs" : "no run estimate: no spread across runs";
  return fmt::format("across runs {:.{}g} ± {:.{}g}", s.mean, digits, s.half_width, digits);
}

Spread spread(std::span<const double> values, double confidence) {
  std::vector<double> finite;
  for (double v : values)
    if (!std::isnan(v)) finite.push_back(v);
  Spread s;
  s.n = finite.size();
  if (finite.empty()) {
    s.mean = s.sd = s.half_width = s.low = s.high = s.min = s.max = kNaN;
    return s;
  }
  for (double v : finite) s.mean += v;
  s.mean /= static_cast<double>(s.n);
  s.min = *std::min_element(finite.begin(), finite.end());
  s.max = *std::max_element(finite.begin(), finite.end());
  s.sd = sample_standard_deviation(finite);
  s.half_width = s.n < 2 ? kNaN
                         : student_t_quantile(1 - (1 - confidence) / 2, static_cast<double>(s.n - 1)) * s.sd /
                               std::sqrt(static_cast<double>(s.n));
  s.low = s.mean - s.half_width;
  s.high = s.mean + s.half_width;
  return s;
}

std::vector<double> holm_adjust(std::span<const double> p) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (std::isnan(p[i])) continue;
    if (!(p[i] >= 0 && p[i] <= 1)) throw InvalidParameter(fmt::format("p[{}]", i), p[i], "a probability in [0, 1] or NaN");
    order.push_back(i);
  }
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return p[a] < p[b]; });
  std::vector<double> adjusted(p.size(), std::numeric_limits<double>::quiet_NaN());
  const double m = static_cast<double>(order.size());
  double running = 0;
  for (std::size_t rank = 0; rank < order.size(); ++rank) {
    running = std::max(running, std::min(1.0, (m - static_cast<double>(rank)) * p[order[rank]]));
    adjusted[order[rank]] = running;
  }
  return adjusted;
}

}  // namespace lmcal
