// The parts of the empirical friction term's search (empirical_friction.cc), private to it:
// the law's columns and the dictionary of candidate terms (empirical_friction_dictionary.cc),
// the smooth alternative (empirical_friction_smooth.cc) and a term in words
// (empirical_friction_words.cc).
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include "lmcal/diagnose/friction_diagnosis.hpp"
#include "sparse_regression.hpp"

namespace lmcal::detail {

// A dictionary entry: the term it stands for (coefficient to be fitted) and its column.
struct DictionaryEntry {
  FrictionTerm term;
  std::vector<double> column;
  std::size_t family = 0;
};

// What the current law gives every row beyond the log's columns: its force, its parts (for
// terms that reweight one) and its slope in the temperature (for terms that shift that input:
// the column of c·g(x) in F_law(T + c·g(x)) is ∂F_law/∂T · g(x), the law's own derivative).
struct LawColumns {
  std::vector<double> law;                     // F_law per row (the current fit's)
  std::vector<std::vector<double>> part;       // per part (coulomb, stribeck, viscous, seal), per row
  std::vector<double> dF_dT;                   // ∂F_law/∂T per row, N/K
};

constexpr TermCovariate kLawParts[] = {TermCovariate::coulomb_N, TermCovariate::stribeck_N, TermCovariate::viscous_N,
                                       TermCovariate::seal_N};

// The column of a term's factor or of a whole term over the log's rows.
struct TermColumns {
  const FrictionLog& log;
  const TermSeries& series;
  const LawColumns& law;
  std::vector<double> factor(const TermFactor& f, double scale) const;
  std::vector<double> column(const FrictionTerm& t) const;
};

// The law's columns at the current fit's parameter values: its force `law` (given), its parts
// and its temperature slope (central difference over ±0.5 K) from `law_warmer(i, ΔT)`, the
// current law at row i with the temperature ΔT higher.
LawColumns law_columns_at(const FrictionLog& log, const std::vector<double>& values, std::vector<double> law, const std::function<double(std::size_t, double)>& law_warmer,
                          double reference_C);

// A part that is the same in every row (the seal offset of one guide) reweighted by a covariate
// is that covariate's own column: only a part that varies is worth its terms.
bool varies_across_rows(const std::vector<double>& part);

// The dictionary. `law_warmer(i, ΔT)`: the current law at row i with the temperature ΔT higher.
std::vector<DictionaryEntry> dictionary(const FrictionLog& log, const TermSeries& series, const LawColumns& law_columns,
                                  const std::function<double(std::size_t, double)>& law_warmer, double reference_C);

// The smooth alternative: cubic B-splines in one covariate that varies within runs (speed,
// load, temperature), 1 to 4 interior knots at quantiles of its values (fewer for a covariate
// of few values; none in temperature), the first basis function left out (the run levels carry
// a constant); the covariate and the knots chosen by leave-one-run-out error, fewer basis
// functions preferred within the tolerance.
struct SmoothChoice {
  std::vector<FrictionTerm> terms;
  double cv_rmse = 0;     // linearised leave-one-run-out RMSE of the runs' shape with it
  std::size_t tried = 0;  // basis functions tried, over all covariates
  std::string why_not;
};

SmoothChoice smooth_term(const FrictionLog& log, const TermSeries& series, const TermColumns& columns, const SparseProblem& linear,
                         double min_gain_percent);

// What a term does, in words.
std::string term_words(const FrictionTerm& t);

// The mechanisms a term resembles, in words ("" when none comes to mind); `chronology` says
// how the runs were put in order (TermSeries::chronology).
std::string resemblance(const FrictionTerm& t, const std::string& chronology);

// The covariate a term is drawn over in the report.
TermCovariate main_covariate(const FrictionTerm& t);

// Whether a term is a B-spline's basis function (of a smooth term).
bool has_spline(const FrictionTerm& t);

}  // namespace lmcal::detail
