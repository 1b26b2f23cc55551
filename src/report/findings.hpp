// What a calibration found and how sure it is, in plain sentences: the first thing the report
// ("What we found") and the terminal (calibrate's summary) say, and calibration.json's
// "findings". Computed once from the Calibration, so the three print the same numbers.
//
//   found:          per model, what the published model misses (each cause with its equation
//                   in words), the held-out error with and without it, the calibrated values
//                   with their 95 % intervals in the quantity's unit;
//   how_sure:       per model, where the intervals come from, in words ("the 6 runs are treated
//                   as repeats: their spread sets the intervals"), without formulas;
//   contradictions: two parts of the result that read as disagreeing, named with why
//                   ("the published model's runs disagree on α; the calibrated model's do not").
//
// The methods' names and formulas are in `method_details` and the terms they use in
// `glossary()`, each defined once; the report puts both one click away (a <details>).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "lmcal/calibrate/calibration.hpp"

namespace lmcal::report {

struct Findings {
  std::vector<std::string> found;
  std::vector<std::string> how_sure;
  std::vector<std::string> contradictions;
  // Per calibrated model: its name and the interval method's full statement with its notes
  // ("hac — residuals within runs …"), for the details.
  std::vector<std::pair<std::string, std::vector<std::string>>> method_details;
};

Findings findings(const Calibration& c);

// The statistical terms the details use, each defined once: term -> definition.
const std::vector<std::pair<std::string, std::string>>& glossary();

}  // namespace lmcal::report
