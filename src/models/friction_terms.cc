#include "lmcal/models/friction_terms.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
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
    case TermCovariate::run_index: return "k";
    case TermCovariate::campaign_time_s: return "t_c";
    case TermCovariate::coulomb_N: return "F_C";
    case TermCovariate::stribeck_N: return "F_St";
    case TermCovariate::viscous_N: return "F_v";
    case TermCovariate::seal_N: return "F_0";
  }
  return "?";
}

constexpr TermCovariate kCovariates[] = {
    TermCovariate::velocity_m_s,    TermCovariate::load_N,         TermCovariate::preload_um,
    TermCovariate::block_length_mm, TermCovariate::temperature_C,  TermCovariate::direction,
    TermCovariate::time_in_run_s,   TermCovariate::sliding_distance_m, TermCovariate::law_force_N,
    TermCovariate::run_index,       TermCovariate::campaign_time_s, TermCovariate::coulomb_N,
    TermCovariate::stribeck_N,      TermCovariate::viscous_N,      TermCovariate::seal_N};

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
    case TermCovariate::run_index: return "run_index";
    case TermCovariate::campaign_time_s: return "campaign_time_s";
    case TermCovariate::coulomb_N: return "coulomb_N";
    case TermCovariate::stribeck_N: return "stribeck_N";
    case TermCovariate::viscous_N: return "viscous_N";
    case TermCovariate::seal_N: return "seal_N";
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
    case TermCovariate::law_force_N:
    case TermCovariate::coulomb_N:
    case TermCovariate::stribeck_N:
    case TermCovariate::viscous_N:
    case TermCovariate::seal_N: return "N";
    case TermCovariate::run_index: return "1";
    case TermCovariate::campaign_time_s: return "s";
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

std::optional<TermCovariate> FrictionTerm::shifted_input() const {
  for (const auto& f : factors)
    if (f.transform == TermTransform::input_shift) return f.covariate;
  return std::nullopt;
}

bool FrictionTerm::uses_law() const {
  return std::any_of(factors.begin(), factors.end(), [](const TermFactor& f) { return is_law_covariate(f.covariate); });
}

std::string FrictionTerm::symbol(std::size_t k) const {
  if (lagged_temperature()) return fmt::format("F_law(T + c{0}·(lag(T; tau{0}) - T)) - F_law(T)", k);
  std::string s = fmt::format("c{}", k);
  const auto input = shifted_input();
  for (const auto& f : factors) {
    if (f.transform == TermTransform::input_shift) continue;
    const char* x = symbol_of(f.covariate);
    const std::string centred = f.centre == 0 ? std::string(x) : fmt::format("({} - {:g})", x, f.centre);
    switch (f.transform) {
      case TermTransform::linear: s += "·" + centred; break;
      case TermTransform::square: s += "·" + centred + "²"; break;
      case TermTransform::decay: s += fmt::format("·exp(-{}/l{})", x, k); break;
      case TermTransform::spline: s += fmt::format("·B{}({})", f.basis, x); break;
      case TermTransform::step: s += fmt::format("·[{} > {:g}]", x, f.centre); break;
      case TermTransform::lagged_temperature:
      case TermTransform::input_shift: break;
    }
  }
  if (input) {
    const char* x = symbol_of(*input);
    return fmt::format("F_law({0} + {1}) - F_law({0})", x, s);
  }
  return s;
}

std::string FrictionTerm::coefficient_unit() const {
  if (lagged_temperature()) return "1";
  std::string per;
  bool relative = false;
  for (const auto& f : factors) {
    if (is_law_covariate(f.covariate)) relative = true;
    if (f.transform == TermTransform::decay || f.transform == TermTransform::spline ||
        f.transform == TermTransform::step || f.transform == TermTransform::input_shift || is_law_covariate(f.covariate))
      continue;
    const std::string u = term_covariate_unit(f.covariate);
    if (u == "1") continue;
    per += (per.empty() ? "" : "·") + u + (f.transform == TermTransform::square ? "²" : "");
  }
  const auto input = shifted_input();
  const std::string numerator = input ? term_covariate_unit(*input) : relative ? "1" : "N";
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

std::string term_form_problem(const FrictionTerm& term) {
  const auto& f = term.factors;
  if (f.empty() || f.size() > 2) return "a term has one or two factors";
  if (term.lagged_temperature() && f.size() != 1) return "a lagged temperature is a term alone";
  std::size_t scales = 0;
  for (std::size_t j = 0; j < f.size(); ++j) {
    scales += f[j].transform == TermTransform::decay || f[j].transform == TermTransform::lagged_temperature;
    if (f[j].transform == TermTransform::input_shift) {
      if (j != 0) return "an input shift is a term's first factor";
      if (f[j].covariate != TermCovariate::temperature_C && f[j].covariate != TermCovariate::velocity_m_s)
        return "an input shift corrects temperature_C or velocity_m_s";
      if (term.uses_law()) return "an input shift's size does not depend on the law";
    }
    if (is_law_covariate(f[j].covariate) && (f[j].transform != TermTransform::linear || f[j].centre != 0))
      return "the law and its parts enter as plain factors (linear, no centre)";
  }
  if (scales > 1) return "a term has at most one decay or lag";
  return "";
}

std::optional<TermCovariate> find_term_covariate(std::string_view name) {
  for (TermCovariate c : kCovariates)
    if (name == term_covariate_name(c)) return c;
  return std::nullopt;
}

namespace {
constexpr std::pair<TermTransform, const char*> kTransforms[] = {{TermTransform::linear, "linear"},
                                                                 {TermTransform::square, "square"},
                                                                 {TermTransform::decay, "decay"},
                                                                 {TermTransform::lagged_temperature, "lagged_temperature"},
                                                                 {TermTransform::spline, "spline"},
                                                                 {TermTransform::step, "step"},
                                                                 {TermTransform::input_shift, "input_shift"}};
}  // namespace

double bspline(const std::vector<double>& knots, int k, double x) {
  constexpr int degree = 3;
  const std::size_t m = knots.size();
  if (m < 2 * (degree + 1) || k < 0 || static_cast<std::size_t>(k) + degree + 1 >= m) return 0;
  x = std::clamp(x, knots.front(), knots.back());
  const auto K = static_cast<std::size_t>(k);
  if (x < knots[K] || x > knots[K + degree + 1]) return 0;  // outside its support (exactly 0 below)
  // Degree 0 on [t_j, t_j+1), the last non-empty interval closed at the right end.
  std::array<double, degree + 1> b{};  // no allocation: it runs per row and basis function
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

namespace {

// Each run's place in the campaign (TermSeries::run_index, chronology) and, with a time
// column, the campaign's time of every row. The runs' clocks are a campaign clock when, taken
// in the order of their first reading, each starts after the one before has ended; otherwise
// the runs follow each other in the order written, median_step apart.
void put_runs_in_order(const FrictionLog& log, double median_step, TermSeries& s) {
  const std::size_t runs = s.run_rows.size();
  std::vector<std::size_t> order;
  for (std::size_t r = 0; r < runs; ++r)
    if (!s.run_rows[r].empty()) order.push_back(r);
  // Written order: by each run's first row.
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return s.run_rows[a].front() < s.run_rows[b].front(); });
  auto first_time = [&](std::size_t r) { return log.time_s[s.run_rows[r].front()]; };
  auto last_time = [&](std::size_t r) {
    double last = -std::numeric_limits<double>::infinity();
    for (std::size_t i : s.run_rows[r]) last = std::max(last, log.time_s[i]);
    return last;
  };
  if (s.timed && order.size() >= 2) {
    std::vector<std::size_t> by_clock = order;
    std::stable_sort(by_clock.begin(), by_clock.end(), [&](std::size_t a, std::size_t b) { return first_time(a) < first_time(b); });
    bool campaign_clock = true;
    for (std::size_t k = 1; k < by_clock.size() && campaign_clock; ++k)
      campaign_clock = first_time(by_clock[k]) > last_time(by_clock[k - 1]);
    if (campaign_clock) {
      order = by_clock;
      s.chronology = "time_s";
    }
  }
  s.run_index.assign(runs, kNaN);
  for (std::size_t k = 0; k < order.size(); ++k) s.run_index[order[k]] = static_cast<double>(k);
  if (!s.timed) return;
  double start = 0;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t r = order[k];
    if (s.chronology == "time_s") start = first_time(r) - first_time(order.front());
    for (std::size_t i : s.run_rows[r]) s.campaign_time_s[i] = start + s.time_in_run_s[i];
    start += last_time(r) - first_time(r) + median_step;
  }
}

}  // namespace

TermSeries term_series(const FrictionLog& log) {
  TermSeries s;
  const std::size_t n = log.size();
  s.run_rows.resize(log.run_names.size());
  for (std::size_t i = 0; i < n; ++i) s.run_rows[log.run[i]].push_back(i);
  s.timed = n > 0 && std::none_of(log.time_s.begin(), log.time_s.end(), [](double t) { return std::isnan(t); });
  s.time_in_run_s.assign(n, kNaN);
  s.sliding_distance_m.assign(n, kNaN);
  s.campaign_time_s.assign(n, kNaN);
  if (!s.timed) {
    put_runs_in_order(log, 0, s);
    return s;
  }
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
  put_runs_in_order(log, median_step, s);
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
    case TermCovariate::run_index: return series.run_index[log.run[i]];
    case TermCovariate::campaign_time_s: return series.campaign_time_s[i];
    case TermCovariate::law_force_N:
    case TermCovariate::coulomb_N:
    case TermCovariate::stribeck_N:
    case TermCovariate::viscous_N:
    case TermCovariate::seal_N: return kNaN;  // the law's, at the parameters: not a column
  }
  return kNaN;
}

}  // namespace lmcal
