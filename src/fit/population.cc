#include "lmcal/fit/population.hpp"

#include <boost/math/distributions/normal.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "lmcal/error.hpp"
#include "lmcal/fit/statistics.hpp"

namespace lmcal {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// No index: subset() leaves nobody out.
constexpr std::size_t kNobody = std::numeric_limits<std::size_t>::max();
// A unit is tested for outliers only against at least this many others.
constexpr std::size_t kMinPopulation = 3;
// The Q-profile's upper bound is searched up to this multiple of the data's variance.
constexpr double kTauSearchSpan = 1e6;

void require_estimate(const char* what, std::size_t i, double value, double se) {
  if (!std::isfinite(value)) throw InvalidParameter(fmt::format("{}[{}].value", what, i), value, "a finite number");
  if (!(std::isfinite(se) && se > 0)) throw InvalidParameter(fmt::format("{}[{}].se", what, i), se, "a finite value > 0");
}

// A probability strictly inside (0, 1): a confidence or a level.
void require_open_unit(const char* parameter, double value) {
  if (!(value > 0 && value < 1)) throw InvalidParameter(parameter, value, "a value in (0, 1)");
}

void require_estimates(std::span<const Estimate> estimates) {
  for (std::size_t i = 0; i < estimates.size(); ++i) require_estimate("estimates", i, estimates[i].value, estimates[i].se);
}

// Two-sided p of a standard normal deviate: 2Φ(−|z|).
double normal_two_sided_p(double z) { return std::erfc(std::abs(z) / std::sqrt(2.0)); }

// ---- Weighted sums with w_i = 1/(s_i² + τ²) -------------------------------------------------

struct WeightedMean {
  double mean = 0;
  double sum_w = 0;
};

WeightedMean weighted_mean(std::span<const Estimate> e, double tau2) {
  WeightedMean m;
  double sum_wy = 0;
  for (const Estimate& x : e) {
    const double w = 1 / (x.se * x.se + tau2);
    m.sum_w += w;
    sum_wy += w * x.value;
  }
  m.mean = sum_wy / m.sum_w;
  return m;
}

// Generalized Q(τ²) = Σ w_i (y_i − μ(τ²))²; Q(0) is Cochran's Q.
double generalized_q(std::span<const Estimate> e, double tau2) {
  const double mu = weighted_mean(e, tau2).mean;
  double q = 0;
  for (const Estimate& x : e) q += (x.value - mu) * (x.value - mu) / (x.se * x.se + tau2);
  return q;
}

// Restricted log-likelihood of τ², up to a constant: −½ [Σ log(s_i² + τ²) + log Σw + Q(τ²)].
double restricted_log_likelihood(std::span<const Estimate> e, double tau2) {
  double log_v = 0;
  for (const Estimate& x : e) log_v += std::log(x.se * x.se + tau2);
  return -0.5 * (log_v + std::log(weighted_mean(e, tau2).sum_w) + generalized_q(e, tau2));
}

// Σ w, Σ w² with w = 1/s² (the fixed-effect weights).
struct FixedWeights {
  double sum_w = 0, sum_w2 = 0;
};

FixedWeights fixed_weights(std::span<const Estimate> e) {
  FixedWeights f;
  for (const Estimate& x : e) {
    const double w = 1 / (x.se * x.se);
    f.sum_w += w;
    f.sum_w2 += w * w;
  }
  return f;
}

double dersimonian_laird_tau2(std::span<const Estimate> e) {
  const FixedWeights f = fixed_weights(e);
  const double dof = static_cast<double>(e.size() - 1);
  return std::max(0.0, (generalized_q(e, 0) - dof) / (f.sum_w - f.sum_w2 / f.sum_w));
}

// The size of the data's variance: the larger of the values' sample variance and the largest s².
double data_variance(std::span<const Estimate> e) {
  std::vector<double> values(e.size());
  double largest_v = 0;
  for (std::size_t i = 0; i < e.size(); ++i) {
    values[i] = e[i].value;
    largest_v = std::max(largest_v, e[i].se * e[i].se);
  }
  const double sd = sample_standard_deviation(values);
  return std::max(sd * sd, largest_v);
}

// ---- REML ---------------------------------------------------------------------------------

struct Reml {
  double tau2 = 0;
  bool converged = false;
};

// Where the REML iteration starts: DerSimonian-Laird, unless τ² = 0 or a log grid (factor 1.5 from
// 1e-3 × the smallest s² to 10 × the data's variance) has a higher restricted likelihood. When
// the SEs differ by orders of magnitude that likelihood can have several maxima, and scoring
// from DL alone can stop on a lower one.
double reml_start(std::span<const Estimate> e, double tau2_dl) {
  double smallest_v = kInf;
  for (const Estimate& x : e) smallest_v = std::min(smallest_v, x.se * x.se);
  double best = tau2_dl, best_loglik = restricted_log_likelihood(e, tau2_dl);
  const auto consider = [&](double tau2) {
    const double loglik = restricted_log_likelihood(e, tau2);
    if (loglik > best_loglik) {
      best = tau2;
      best_loglik = loglik;
    }
  };
  consider(0);
  const double top = 10 * data_variance(e);
  for (double tau2 = 1e-3 * smallest_v; tau2 < top; tau2 *= 1.5) consider(tau2);
  return best;
}

// Maximizes the restricted likelihood from `start` (Viechtbauer 2005), with P = W − W11ᵀW/Σw:
//   score = ½ [yᵀP²y − tr P],  observed information = yᵀP³y − ½ tr P²,  expected = ½ tr P².
// A Newton step where the observed information is positive (it converges in a few steps where
// Fisher scoring crawls, when the SEs differ widely), a Fisher scoring step elsewhere; a step that
// lowers the likelihood is halved; τ² is kept >= 0. Needs k >= 2. reml_step is one step from τ².
double reml_step(std::span<const Estimate> e, double tau2) {
  const double mu = weighted_mean(e, tau2).mean;
  double sw = 0, sw2 = 0, sw3 = 0, swr = 0, swr2 = 0, sw3r2 = 0;  // r_i = w_i (y_i − μ) = (Py)_i
  for (const Estimate& x : e) {
    const double w = 1 / (x.se * x.se + tau2), residual = w * (x.value - mu);
    sw += w;
    sw2 += w * w;
    sw3 += w * w * w;
    swr += w * residual;
    swr2 += residual * residual;
    sw3r2 += w * residual * residual;
  }
  const double trace_p = sw - sw2 / sw;
  const double trace_p2 = sw2 - 2 * sw3 / sw + (sw2 / sw) * (sw2 / sw);
  const double score = 0.5 * (swr2 - trace_p);
  const double observed = (sw3r2 - swr * swr / sw) - 0.5 * trace_p2;
  return score / (observed > 0 ? observed : 0.5 * trace_p2);
}

// The size τ² changes are judged against (with τ²): the mean s².
double mean_variance(std::span<const Estimate> e) {
  double sum = 0;
  for (const Estimate& x : e) sum += x.se * x.se;
  return sum / static_cast<double>(e.size());
}

Reml reml_tau2(std::span<const Estimate> e, double start) {
  const double scale = mean_variance(e);

  Reml r{start, false};
  double loglik = restricted_log_likelihood(e, r.tau2);
  for (int iteration = 0; iteration < 200 && !r.converged; ++iteration) {
    double next = std::max(0.0, r.tau2 + reml_step(e, r.tau2));
    double next_loglik = restricted_log_likelihood(e, next);
    for (int halving = 0; halving < 60 && next_loglik < loglik; ++halving) {
      next = 0.5 * (r.tau2 + next);
      next_loglik = restricted_log_likelihood(e, next);
    }
    r.converged = std::abs(next - r.tau2) <= 1e-12 * (scale + r.tau2);
    if (next_loglik >= loglik) {
      r.tau2 = next;
      loglik = next_loglik;
    }
  }
  return r;
}

// ---- The population's centre: what the leave-one-out deviations need ---------------------

struct Centre {
  double mean = kNaN, mean_se = kNaN, tau2 = kNaN, tau2_dl = kNaN;
  bool converged = false;
};

// From this many estimates on, a leave-one-out fit starts at the maximum of all members (one unit
// of k moves it by O(1/k)) and takes plain REML steps, without the grid search and the
// likelihood's logarithms: k fits of a few passes each, which keeps a fleet of thousands of
// units to about a second (bench/fleet_bench.cpp). A start from which the steps do not settle
// falls back to the full search.
constexpr std::size_t kNearStartUnits = 30;

// REML steps from `start` until they settle (true, `tau2` the maximum) or 30 steps pass (false).
bool newton_from(std::span<const Estimate> e, double start, double& tau2) {
  const double scale = mean_variance(e);
  tau2 = start;
  for (int i = 0; i < 30; ++i) {
    const double next = std::max(0.0, tau2 + reml_step(e, tau2));
    const bool settled = std::abs(next - tau2) <= 1e-10 * (scale + tau2);
    tau2 = next;
    if (settled) return true;
  }
  return false;
}

// REML τ² and the HKSJ mean for k >= 2; for k = 1 the estimate itself, τ unknown. `near`: the
// members' REML τ², from which a leave-one-out fit of kNearStartUnits or more starts.
Centre fit_centre(std::span<const Estimate> e, double near = kNaN) {
  Centre c;
  if (e.size() == 1) {
    c.mean = e[0].value;
    c.mean_se = e[0].se;
    return c;
  }
  if (std::isfinite(near) && e.size() >= kNearStartUnits) c.converged = newton_from(e, near, c.tau2);
  if (!c.converged) {
    c.tau2_dl = dersimonian_laird_tau2(e);
    const Reml reml = reml_tau2(e, reml_start(e, c.tau2_dl));
    c.tau2 = reml.tau2;
    c.converged = reml.converged;
  }
  const WeightedMean m = weighted_mean(e, c.tau2);
  const double q_hk = generalized_q(e, c.tau2) / static_cast<double>(e.size() - 1);
  c.mean = m.mean;
  c.mean_se = std::sqrt(std::max(1.0, q_hk) / m.sum_w);
  return c;
}

// ---- Q-profile interval of τ² -------------------------------------------------------------

// The τ² where the decreasing Q(τ²) falls to `target`: 0 when Q(0) <= target already, +inf when
// it is not reached below kTauSearchSpan × `variance`. Bracketed by doubling, then bisected.
double q_profile_bound(std::span<const Estimate> e, double target, double variance) {
  if (generalized_q(e, 0) <= target) return 0;
  const double cap = kTauSearchSpan * variance;
  double lo = 0, hi = 1e-6 * variance;
  while (generalized_q(e, hi) > target) {
    if (hi > cap) return kInf;
    lo = hi;
    hi *= 2;
  }
  for (int i = 0; i < 200 && hi - lo > 1e-14 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (generalized_q(e, mid) > target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// ---- Outliers -----------------------------------------------------------------------------

// The estimates of `members` but `leave_out`.
std::vector<Estimate> subset(std::span<const Estimate> e, const std::vector<std::size_t>& members, std::size_t leave_out) {
  std::vector<Estimate> out;
  out.reserve(members.size());
  for (std::size_t j : members)
    if (j != leave_out) out.push_back(e[j]);
  return out;
}

// Unit i against the centre of `members` other than i: its deviation z and the Student t dof
// (others − 1) its p is read with. NaN when fewer than 2 others remain.
struct Deviation {
  double z = kNaN;
  double dof = kNaN;
  double p() const { return std::isnan(z) ? kNaN : student_t_two_sided_p(z, dof); }
};

Deviation leave_one_out(std::span<const Estimate> e, const std::vector<std::size_t>& members, std::size_t i,
                        double members_tau2) {
  const std::vector<Estimate> others = subset(e, members, i);
  if (others.size() < 2) return {};
  const Centre c = fit_centre(others, members_tau2);
  return {(e[i].value - c.mean) / std::sqrt(e[i].se * e[i].se + c.tau2 + c.mean_se * c.mean_se),
          static_cast<double>(others.size() - 1)};
}

// ---- Drift --------------------------------------------------------------------------------

void require_series(std::span<const DatedEstimate> series) {
  for (std::size_t i = 0; i < series.size(); ++i) {
    const DatedEstimate& d = series[i];
    if (!std::isfinite(d.day)) throw InvalidParameter(fmt::format("series[{}].day", i), d.day, "a finite number");
    if (i > 0 && !(d.day > series[i - 1].day))
      throw InvalidParameter(fmt::format("series[{}].day", i), d.day,
                             fmt::format("a day after the previous entry's {} (days strictly increasing)", series[i - 1].day));
    require_estimate("series", i, d.value, d.se);
  }
}

// Σw, Σw y and Σw y² of dates [from, to), w = 1/s².
struct WeightedSums {
  double w = 0, wy = 0, wy2 = 0;
  double mean() const { return wy / w; }
  double chi2() const { return std::max(0.0, wy2 - wy * wy / w); }  // Σ w (y − mean)²
};

WeightedSums weighted_sums(std::span<const DatedEstimate> s, std::size_t from, std::size_t to) {
  WeightedSums out;
  for (std::size_t i = from; i < to; ++i) {
    const double w = 1 / (s[i].se * s[i].se);
    out.w += w;
    out.wy += w * s[i].value;
    out.wy2 += w * s[i].value * s[i].value;
  }
  return out;
}

// A weighted estimate against 0, its se0 from the stated SEs, χ² on dof the scatter about the
// model. Within the SEs (χ² <= dof) they are trusted: se = se0 and a normal p. Beyond them the
// se is widened to se0 · sqrt(χ²/dof) and read with Student t on dof (the variance is then
// estimated). A t on the floored se would be conservative twice over (under 1 % at 5 % for 8 dates).
struct ScaledTest {
  double se = kNaN;
  double p = kNaN;
};

ScaledTest scaled_test(double estimate, double se0, double chi2, double dof) {
  if (chi2 <= dof) return {se0, normal_two_sided_p(estimate / se0)};
  const double se = se0 * std::sqrt(chi2 / dof);
  return {se, student_t_two_sided_p(estimate / se, dof)};
}

void fit_trend(std::span<const DatedEstimate> s, Drift& d) {
  double sw = 0, swt = 0, swy = 0;
  for (const DatedEstimate& x : s) {
    const double w = 1 / (x.se * x.se);
    sw += w;
    swt += w * x.day;
    swy += w * x.value;
  }
  const double t_bar = swt / sw, y_bar = swy / sw;
  double stt = 0, sty = 0;
  for (const DatedEstimate& x : s) {
    const double w = 1 / (x.se * x.se);
    stt += w * (x.day - t_bar) * (x.day - t_bar);
    sty += w * (x.day - t_bar) * (x.value - y_bar);
  }
  const double slope = sty / stt;
  const auto line = [&](double day) { return y_bar + slope * (day - t_bar); };
  double chi2 = 0;
  for (const DatedEstimate& x : s) chi2 += std::pow((x.value - line(x.day)) / x.se, 2);
  const ScaledTest test = scaled_test(slope, 1 / std::sqrt(stt), chi2, static_cast<double>(s.size() - 2));
  d.slope_per_day = slope;
  d.slope_se = test.se;
  d.trend_p = test.p;
  const double first = line(s.front().day), last = line(s.back().day);
  d.trend_percent = first == 0 ? kNaN : (last - first) / std::abs(first) * 100;
}

// The maximum-likelihood split (least χ²_c, i.e. largest unscaled |Δ|/se0(Δ)); its p falls
// monotonically with that statistic, so it is also the split of least p.
void fit_change_point(std::span<const DatedEstimate> s, Drift& d) {
  const std::size_t n = s.size();
  double best_z = -1, best_p = kNaN;
  for (std::size_t c = 2; c + 2 <= n; ++c) {
    const WeightedSums before = weighted_sums(s, 0, c), after = weighted_sums(s, c, n);
    const double shift = after.mean() - before.mean(), se0 = std::sqrt(1 / before.w + 1 / after.w);
    if (std::abs(shift) / se0 <= best_z) continue;
    best_z = std::abs(shift) / se0;
    best_p = scaled_test(shift, se0, before.chi2() + after.chi2(), static_cast<double>(n - 2)).p;
    d.change_index = c;
    d.shift = shift;
    d.shift_percent = before.mean() == 0 ? kNaN : shift / std::abs(before.mean()) * 100;
  }
  d.change_p = std::min(1.0, static_cast<double>(n - 3) * best_p);
}

}  // namespace

RandomEffects random_effects(std::span<const Estimate> estimates, double confidence) {
  require_open_unit("confidence", confidence);
  require_estimates(estimates);
  RandomEffects r;
  r.k = estimates.size();
  if (r.k == 0) {
    r.method = "no estimates";
    return r;
  }
  const double upper = 0.5 * (1 + confidence), lower = 0.5 * (1 - confidence);
  const Centre c = fit_centre(estimates);
  r.mean = c.mean;
  r.mean_se = c.mean_se;
  if (r.k == 1) {
    const double z = boost::math::quantile(boost::math::normal_distribution<double>(), upper);
    r.mean_low = r.mean - z * r.mean_se;
    r.mean_high = r.mean + z * r.mean_se;
    r.method = "one estimate: the mean is that estimate with its own se (normal interval); "
               "no between-unit spread can be estimated from one unit";
    return r;
  }
  const double dof = static_cast<double>(r.k - 1);
  const double t = student_t_quantile(upper, dof);
  r.mean_low = r.mean - t * r.mean_se;
  r.mean_high = r.mean + t * r.mean_se;
  r.tau = std::sqrt(c.tau2);
  r.tau_dl = std::sqrt(c.tau2_dl);
  r.converged = c.converged;

  const double variance = data_variance(estimates);
  r.tau_low = std::sqrt(q_profile_bound(estimates, chi_squared_quantile(upper, dof), variance));
  r.tau_high = std::sqrt(q_profile_bound(estimates, chi_squared_quantile(lower, dof), variance));

  r.q = generalized_q(estimates, 0);
  r.q_p = chi_squared_upper_p(r.q, dof);
  const FixedWeights f = fixed_weights(estimates);
  const double typical_v = dof * f.sum_w / (f.sum_w * f.sum_w - f.sum_w2);
  r.i2 = c.tau2 / (c.tau2 + typical_v);

  r.method = "REML tau (Newton/Fisher scoring from DerSimonian-Laird or a better tau grid point), "
             "Q-profile tau interval, Hartung-Knapp-Sidik-Jonkman mean interval (t, k - 1 dof, scaled by max(1, q))";
  if (!r.converged) r.method += "; REML did not converge, tau is its last iterate";
  if (std::isinf(r.tau_high)) r.method += "; tau upper bound unbounded (+inf): too few units to bound the spread";
  return r;
}

PopulationFit fit_population(std::span<const Estimate> estimates, std::size_t family_size, double alpha) {
  if (family_size < 1) throw InvalidParameter("family_size", 0.0, "at least 1");
  require_open_unit("alpha", alpha);
  require_estimates(estimates);
  const std::size_t n = estimates.size();
  const double family = static_cast<double>(family_size);

  std::vector<std::size_t> members(n);  // units not flagged, ascending
  std::iota(members.begin(), members.end(), std::size_t{0});
  PopulationFit fit;
  for (;;) {
    if (members.size() < kMinPopulation + 1) {
      fit.note = fit.outliers.empty()
                     ? fmt::format("no unit tested: {} units leave fewer than {} others to fit", n, kMinPopulation)
                     : fmt::format("stopped: fewer than {} others would be left to fit", kMinPopulation);
      break;
    }
    if (2 * (fit.outliers.size() + 1) > n) {
      fit.note = "stopped: half the units are flagged";
      break;
    }
    std::size_t worst = 0;
    double worst_z = -1;
    Deviation worst_deviation;
    const double members_tau2 = fit_centre(subset(estimates, members, kNobody)).tau2;
    for (std::size_t i : members) {
      const Deviation d = leave_one_out(estimates, members, i, members_tau2);
      if (std::abs(d.z) > worst_z) {
        worst_z = std::abs(d.z);
        worst = i;
        worst_deviation = d;
      }
    }
    const double p = worst_deviation.p() * static_cast<double>(members.size()) * family;
    if (!(p < alpha)) {
      fit.note = fmt::format("stopped: the most extreme unit left ({}) has Bonferroni {} >= {}", worst,
                             p_is(std::min(1.0, p)), alpha);
      break;
    }
    fit.outliers.push_back(worst);
    std::erase(members, worst);
  }
  std::sort(fit.outliers.begin(), fit.outliers.end());

  const std::vector<Estimate> population = subset(estimates, members, kNobody);
  fit.population = random_effects(population);
  fit.z.resize(n);
  fit.p_adjusted.resize(n);
  const double members_tau2 = fit.population.tau * fit.population.tau;
  for (std::size_t i = 0; i < n; ++i) {
    const Deviation d = leave_one_out(estimates, members, i, members_tau2);  // a flagged unit is not a member: all members are its others
    fit.z[i] = d.z;
    fit.p_adjusted[i] = std::min(1.0, d.p() * static_cast<double>(n) * family);
  }
  return fit;
}

Drift drift_test(std::span<const DatedEstimate> series) {
  require_series(series);
  Drift d;
  d.n = series.size();
  if (d.n < 3) {
    d.note = "no drift test: a trend needs at least 3 dates";
    return d;
  }
  fit_trend(series, d);
  if (d.n < 4) {
    d.note = "no change-point test: it needs at least 4 dates (2 on each side)";
    d.p = d.trend_p;
    return d;
  }
  fit_change_point(series, d);
  d.p = std::min(1.0, 2 * std::min(d.trend_p, d.change_p));
  return d;
}

}  // namespace lmcal
