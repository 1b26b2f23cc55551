#include "lmcal/models/friction_terms.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <utility>

namespace lmcal {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// The symbol of a covariate in formulas.
const char* symbol_of(TermCovariate c) {
  switch (c) {
    case TermCovariate::velocity_m_s: return "V";
    case TermCovariate::load_N: return "P";
    case TermCovariate::preload_um: return "pc";
    case TermCovariate::block_length_mm: return "Lb";
    case TermCovariate::temperature_C: return "T";
    case TermCovariate::direction: return "dir";
    case TermCovariate::time_in_run_s: return "t";
    case TermCovariate::sliding_distance_m: return "s";
    case TermCovariate::law_force_N: return "F_law";
  }
  return "?";
}

}  // namespace

const char* term_covariate_name(TermCovariate c) {
  switch (c) {
    case TermCovariate::velocity_m_s: return "velocity_m_s";
    case TermCovariate::load_N: return "load_N";
    case TermCovariate::preload_um: return "preload_um";
    case TermCovariate::block_length_mm: return "block_length_mm";
    case TermCovariate::temperature_C: return "temperature_C";
    case TermCovariate::direction: return "direction";
    case TermCovariate::time_in_run_s: return "time_in_run_s";
    case TermCovariate::sliding_distance_m: return "sliding_distance_m";
    case TermCovariate::law_force_N: return "friction_law_N";
  }
  return "?";
}

const char* term_covariate_unit(TermCovariate c) {
  switch (c) {
    case TermCovariate::velocity_m_s: return "m/s";
    case TermCovariate::load_N: return "N";
    case TermCovariate::preload_um: return "um";
    case TermCovariate::block_length_mm: return "mm";
    case TermCovariate::temperature_C: return "K";
    case TermCovariate::direction: return "1";
    case TermCovariate::time_in_run_s: return "s";
    case TermCovariate::sliding_distance_m: return "m";
    case TermCovariate::law_force_N: return "N";
  }
  return "?";
}

bool FrictionTerm::has_scale() const {
  return std::any_of(factors.begin(), factors.end(), [](const TermFactor& f) {
    return f.transform == TermTransform::decay || f.transform == TermTransform::lagged_temperature;
  });
}

bool FrictionTerm::lagged_temperature() const {
  return std::any_of(factors.begin(), factors.end(),
                     [](const TermFactor& f) { return f.transform == TermTransform::lagged_temperature; });
}

std::string FrictionTerm::symbol(std::size_t k) const {
  if (lagged_temperature()) return fmt::format("F_law(T + c{0}·(lag(T; tau{0}) - T)) - F_law(T)", k);
  std::string s = fmt::format("c{}", k);
  for (const auto& f : factors) {
    const char* x = symbol_of(f.covariate);
    const std::string centred = f.centre == 0 ? std::string(x) : fmt::format("({} - {:g})", x, f.centre);
    switch (f.transform) {
      case TermTransform::linear: s += "·" + centred; break;
      case TermTransform::square: s += "·" + centred + "²"; break;
      case TermTransform::decay: s += fmt::format("·exp(-{}/l{})", x, k); break;
      case TermTransform::spline: s += fmt::format("·B{}({})", f.basis, x); break;
      case TermTransform::lagged_temperature: break;
    }
  }
  return s;
}

std::string FrictionTerm::coefficient_unit() const {
  if (lagged_temperature()) return "1";
  std::string per;
  bool relative = false;
  for (const auto& f : factors) {
    if (f.covariate == TermCovariate::law_force_N) relative = true;
    if (f.transform == TermTransform::decay || f.transform == TermTransform::spline ||
        f.covariate == TermCovariate::law_force_N)
      continue;
    const std::string u = term_covariate_unit(f.covariate);
    if (u == "1") continue;
    per += (per.empty() ? "" : "·") + u + (f.transform == TermTransform::square ? "²" : "");
  }
  const std::string numerator = relative ? "1" : "N";
  return per.empty() ? numerator : numerator + "/(" + per + ")";
}

std::string FrictionTerm::scale_unit() const {
  for (const auto& f : factors)
    if (f.transform == TermTransform::decay || f.transform == TermTransform::lagged_temperature)
      return f.transform == TermTransform::lagged_temperature ? "s" : term_covariate_unit(f.covariate);
  return "";
}

std::vector<std::string> FrictionTerm::covariates() const {
  std::vector<std::string> out;
  for (const auto& f : factors) {
    out.push_back(term_covariate_name(f.covariate));
    if (f.transform == TermTransform::lagged_temperature) out.push_back("time_in_run_s");
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::optional<TermCovariate> find_term_covariate(std::string_view name) {
  for (TermCovariate c : {TermCovariate::velocity_m_s, TermCovariate::load_N, TermCovariate::preload_um,
                          TermCovariate::block_length_mm, TermCovariate::temperature_C, TermCovariate::direction,
                          TermCovariate::time_in_run_s, TermCovariate::sliding_distance_m, TermCovariate::law_force_N})
    if (name == term_covariate_name(c)) return c;
  return std::nullopt;
}

namespace {
constexpr std::pair<TermTransform, const char*> kTransforms[] = {{TermTransform::linear, "linear"},
                                                                 {TermTransform::square, "square"},
                                                                 {TermTransform::decay, "decay"},
                                                                 {TermTransform::lagged_temperature, "lagged_temperature"},
                                                                 {TermTransform::spline, "spline"}};
}  // namespace

double bspline(const std::vector<double>& knots, int k, double x) {
  constexpr int degree = 3;
  const std::size_t m = knots.size();
  if (m < 2 * (degree + 1) || k < 0 || static_cast<std::size_t>(k) + degree + 1 >= m) return 0;
  x = std::clamp(x, knots.front(), knots.back());
  // Degree 0 on [t_j, t_j+1), the last non-empty interval closed at the right end.
  std::vector<double> b(degree + 1);
  const auto K = static_cast<std::size_t>(k);
  std::size_t last = m - 1;
  while (last > 0 && knots[last - 1] == knots.back()) --last;  // the last interval with t_j < t_end
  for (int j = 0; j <= degree; ++j) {
    const std::size_t i = K + static_cast<std::size_t>(j);
    const bool inside = x >= knots[i] && (x < knots[i + 1] || (x == knots.back() && i + 1 == last));
    b[static_cast<std::size_t>(j)] = inside ? 1.0 : 0.0;
  }
  for (int d = 1; d <= degree; ++d)
    for (int j = 0; j + d <= degree; ++j) {
      const std::size_t i = K + static_cast<std::size_t>(j);
      const double left = knots[i + static_cast<std::size_t>(d)] - knots[i];
      const double right = knots[i + static_cast<std::size_t>(d) + 1] - knots[i + 1];
      double v = 0;
      if (left > 0) v += (x - knots[i]) / left * b[static_cast<std::size_t>(j)];
      if (right > 0) v += (knots[i + static_cast<std::size_t>(d) + 1] - x) / right * b[static_cast<std::size_t>(j) + 1];
      b[static_cast<std::size_t>(j)] = v;
    }
  return b[0];
}

std::string factor_text(const TermFactor& f) {
  std::string transform;
  for (const auto& [t, name] : kTransforms)
    if (t == f.transform) transform = name;
  std::string text = transform + ":" + term_covariate_name(f.covariate);
  if (f.transform == TermTransform::spline) return text + fmt::format(":{}:{}", f.basis, fmt::join(f.knots, ";"));
  if (f.centre != 0) text += fmt::format(":{}", f.centre);
  return text;
}

std::optional<TermFactor> parse_factor(std::string_view text) {
  const auto first = text.find(':');
  if (first == std::string_view::npos) return std::nullopt;
  const auto second = text.find(':', first + 1);
  TermFactor f;
  bool known = false;
  for (const auto& [t, name] : kTransforms)
    if (text.substr(0, first) == name) f.transform = t, known = true;
  const auto covariate = find_term_covariate(text.substr(first + 1, second == std::string_view::npos ? second : second - first - 1));
  if (!known || !covariate) return std::nullopt;
  f.covariate = *covariate;
  auto number = [](std::string_view t, double& out) {
    const std::string copy(t);
    char* end = nullptr;
    out = std::strtod(copy.c_str(), &end);
    return !copy.empty() && end == copy.c_str() + copy.size() && std::isfinite(out);
  };
  if (f.transform == TermTransform::spline) {  // spline:covariate:basis:k1;k2;…
    if (second == std::string_view::npos) return std::nullopt;
    const auto third = text.find(':', second + 1);
    double basis = 0;
    if (third == std::string_view::npos || !number(text.substr(second + 1, third - second - 1), basis)) return std::nullopt;
    f.basis = static_cast<int>(basis);
    std::string_view rest = text.substr(third + 1);
    while (!rest.empty()) {
      const auto semi = rest.find(';');
      double knot = 0;
      if (!number(rest.substr(0, semi), knot)) return std::nullopt;
      f.knots.push_back(knot);
      rest = semi == std::string_view::npos ? std::string_view{} : rest.substr(semi + 1);
    }
    if (f.knots.size() < 8 || f.basis < 0 || static_cast<std::size_t>(f.basis) + 4 >= f.knots.size() ||
        !std::is_sorted(f.knots.begin(), f.knots.end()))
      return std::nullopt;
    return f;
  }
  if (second != std::string_view::npos) {
    const std::string centre(text.substr(second + 1));
    char* end = nullptr;
    f.centre = std::strtod(centre.c_str(), &end);
    if (centre.empty() || end != centre.c_str() + centre.size() || !std::isfinite(f.centre)) return std::nullopt;
  }
  return f;
}

double steady_term_N(const FrictionTerm& term, const FrictionConditions<double>& c, double law_N, bool* outside) {
  auto value_of = [&](TermCovariate covariate) {
    switch (covariate) {
      case TermCovariate::velocity_m_s: return c.velocity_m_s;
      case TermCovariate::load_N: return c.load_N;
      case TermCovariate::preload_um: return c.preload_um;
      case TermCovariate::block_length_mm: return c.block_length_mm;
      case TermCovariate::temperature_C: return c.temperature_C;
      case TermCovariate::direction: return c.direction;
      case TermCovariate::law_force_N: return law_N;
      default: return kNaN;  // time and distance: no steady value
    }
  };
  if (outside)
    for (const auto& r : term.seen) {
      const double x = value_of(r.covariate);
      if (!std::isnan(x) && (x < r.min || x > r.max)) *outside = true;
    }
  if (term.lagged_temperature()) return 0;  // the lagged temperature has caught up
  double value = term.coefficient;
  for (const auto& f : term.factors) {
    if (f.transform == TermTransform::decay) return 0;  // settled
    if (f.transform == TermTransform::spline) {
      value *= bspline(f.knots, f.basis, value_of(f.covariate));
      continue;
    }
    const double x = value_of(f.covariate) - f.centre;
    value *= f.transform == TermTransform::square ? x * x : x;
  }
  return value;
}

TermSeries term_series(const FrictionLog& log) {
  TermSeries s;
  const std::size_t n = log.size();
  s.run_rows.resize(log.run_names.size());
  for (std::size_t i = 0; i < n; ++i) s.run_rows[log.run[i]].push_back(i);
  s.timed = n > 0 && std::none_of(log.time_s.begin(), log.time_s.end(), [](double t) { return std::isnan(t); });
  s.time_in_run_s.assign(n, kNaN);
  s.sliding_distance_m.assign(n, kNaN);
  if (!s.timed) return s;
  // The typical step, for the boundary between runs.
  std::vector<double> steps;
  for (const auto& rows : s.run_rows)
    for (std::size_t k = 1; k < rows.size(); ++k) steps.push_back(log.time_s[rows[k]] - log.time_s[rows[k - 1]]);
  double median_step = 0;
  if (!steps.empty()) {
    std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
    median_step = std::max(steps[steps.size() / 2], 0.0);
  }
  for (const auto& rows : s.run_rows)
    for (std::size_t i : rows) s.time_in_run_s[i] = log.time_s[i] - log.time_s[rows.front()];
  // Distance in row order: runs in the order they are written.
  double distance = 0;
  for (std::size_t i = 0; i < n; ++i) {
    s.sliding_distance_m[i] = distance;
    const bool same_run_next = i + 1 < n && log.run[i + 1] == log.run[i];
    const double dt = same_run_next ? std::max(log.time_s[i + 1] - log.time_s[i], 0.0) : median_step;
    distance += log.velocity_m_s[i] * dt;
  }
  return s;
}

double term_covariate_value(const FrictionLog& log, const TermSeries& series, std::size_t i, TermCovariate c) {
  switch (c) {
    case TermCovariate::velocity_m_s: return log.velocity_m_s[i];
    case TermCovariate::load_N: return log.load_N[i];
    case TermCovariate::preload_um: return log.preload_um[i];
    case TermCovariate::block_length_mm: return log.block_length_mm[i];
    case TermCovariate::temperature_C: return log.temperature_C[i];
    case TermCovariate::direction: return log.direction[i];
    case TermCovariate::time_in_run_s: return series.time_in_run_s[i];
    case TermCovariate::sliding_distance_m: return series.sliding_distance_m[i];
    case TermCovariate::law_force_N: return kNaN;  // the law's, at the parameters: not a column
  }
  return kNaN;
}

}  // namespace lmcal
