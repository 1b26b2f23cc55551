// lmcal diagnose friction LOG.csv…: what the published friction law gets wrong on these
// data, the named cause, and the gain on held-out runs (friction_diagnosis.hpp).
// Writes DIR/NAME.json and prints the verdict in plain words.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "cli_common.hpp"
#include "output_mode.hpp"
#include "lmcal/io/hash.hpp"
#include "lmcal/io/output_record.hpp"
#include "lmcal/diagnose/friction_diagnosis.hpp"
#include "lmcal/diagnose/thermal_diagnosis.hpp"
#include "lmcal/fit/statistics.hpp"
#include "lmcal/io/atomic_file.hpp"
#include "progress.hpp"

namespace lmcal::cli {

namespace {

struct DiagnoseFrictionOptions {
  std::vector<std::string> files;
  FrictionInputOptions input;
  std::string name = "friction_diagnosis";
  std::string output_dir = "fits";
  FrictionConstantOptions constants;
  FrictionDiagnosisOptions diagnosis;
};

// The width of the widest name of `items` (in code points, as fmt pads), at least `least`: a
// column that holds them all.
template <class Items, class Name>
std::size_t widest(const Items& items, const Name& name, std::size_t least) {
  std::size_t width = least;
  for (const auto& item : items) {
    const std::string text = name(item);
    width = std::max(width, static_cast<std::size_t>(std::count_if(text.begin(), text.end(), [](char c) {
                              return (static_cast<unsigned char>(c) & 0xC0) != 0x80;
                            })));
  }
  return width;
}

// The residuals against the covariates, and every forward step's candidates.
void print_covariates(const std::vector<CovariateTest>& covariates, const char* unit) {
  const std::size_t width = widest(covariates, [](const CovariateTest& c) -> const std::string& { return c.covariate; }, 24);
  for (const auto& c : covariates)
    std::cout << fmt::format("  {:<{}} strength {:.3f}  size {:.4g} {}  p {}{}\n", c.covariate, width, c.correlation, c.size, unit,
                             p_value_text(c.p_value), c.structured ? "  <- structured" : "");
}

// A candidate's estimate with its unit ("149.9 ± 0.401 N s2/m2"), or why it has none: a fit that
// failed (its reason follows), a switch (on or off: no value, and not nested, so BIC decides
// rather than a likelihood-ratio test), a parameter the data do not identify (no standard error).
std::string estimate_text(const CandidateScore& c) {
  const std::string unit = c.unit.empty() || c.unit == "1" ? "" : " " + c.unit;
  if (!std::isfinite(c.cv_rmse)) return "n/a (the fit failed)";
  if (!std::isfinite(c.value)) return "n/a (a switch: BIC decides)";
  if (!std::isfinite(c.se)) return fmt::format("{:.4g}{} ± n/a (not identified)", c.value, unit);
  return fmt::format("{:.4g} ± {:.3g}{}", c.value, c.se, unit);
}

// A held-out RMSE with its gain, "0.6829 N (+38.45 %)"; "n/a" where the fit failed.
std::string held_out_text(double rmse, double gain_percent, const char* unit) {
  if (!std::isfinite(rmse) || !std::isfinite(gain_percent)) return "n/a";
  return fmt::format("{:.4f} {} ({:+.2f} %)", rmse, unit, gain_percent);
}

void print_rounds(const std::vector<std::vector<CandidateScore>>& rounds, const char* unit) {
  for (std::size_t r = 0; r < rounds.size(); ++r) {
    std::cout << fmt::format("candidates, step {} (estimate, likelihood-ratio test, held-out RMSE and gain against the model "
                             "so far, decision):\n",
                             r + 1);
    const std::size_t width = widest(rounds[r], [](const CandidateScore& c) -> const std::string& { return shown_name(c); }, 20);
    const std::size_t estimate_width = widest(rounds[r], estimate_text, 20);
    for (const auto& c : rounds[r])
      std::cout << fmt::format("  {:<{}} {:<{}} LRT p {:<8} held-out {}{}  {}{}\n", shown_name(c), width, estimate_text(c), estimate_width,
                               std::isfinite(c.lrt_p) ? p_value_text(c.lrt_p) : "n/a", held_out_text(c.cv_rmse, c.cv_gain_percent, unit),
                               std::isfinite(c.cv_shape_gain_percent)
                                   ? ", shape " + held_out_text(c.cv_shape_rmse, c.cv_shape_gain_percent, unit)
                                   : "",
                               c.accepted ? "ACCEPTED: " : "", c.reason);
  }
}

void print_lack_of_fit(const LackOfFit& l, const char* unit) {
  if (!l.tested) std::cout << "lack of fit: not tested (" << l.basis << ")\n";
  else
    std::cout << fmt::format("lack of fit against {}: F {:.3g} on ({:.0f}, {:.0f}) dof, p {}, {:.3g} {} beyond a noise of {:.3g} {}{}\n",
                             l.basis, l.statistic, l.df1, l.df2, p_value_text(l.p_value), l.lack_rms, unit, l.pure_error_rms, unit,
                             l.fits ? "" : "  <- structure remains: the model misses");
}

// The term learned beyond the library, one line per component.
void print_empirical(const EmpiricalFinding& e, const char* unit) {
  if (!e.searched) return;
  if (!e.found) {
    std::cout << "beyond the library: no empirical term (" << e.reason << ")\n";
    return;
  }
  std::cout << fmt::format("beyond the library: an empirical term ({} form; learned from the residuals, not a named cause), "
                           "added to {}:\n",
                           e.form, e.where);
  for (const auto& c : e.components) {
    std::cout << fmt::format("  {:<30} {} = {:.4g} [{:.4g}, {:.4g}] {}", c.symbol, c.coefficient.name, c.coefficient.value,
                             c.coefficient.ci_low, c.coefficient.ci_high, c.coefficient.unit);
    if (c.has_scale)
      std::cout << fmt::format(", {} = {:.4g} [{:.4g}, {:.4g}] {}", c.scale.name, c.scale.value, c.scale.ci_low, c.scale.ci_high,
                               c.scale.unit);
    std::cout << "\n";
  }
  std::cout << fmt::format("  {} {:.4g} -> {:.4g} {} ({:.1f} % better){}\n", held_out_criterion_words(e.criterion), e.cv_rmse_before,
                           e.cv_rmse_after, unit, e.cv_gain_percent, e.resembles.empty() ? "" : "; resembles " + e.resembles);
}

// From the baseline to the final model, each step with its models' held-out RMSEs.
void print_steps(const std::vector<DiagnosisStep>& steps, const char* unit) {
  for (const auto& s : steps)
    std::cout << fmt::format("step: {} {}: held-out RMSE {:.4g} -> {:.4g} {}{} ({:+.1f} % on the {})\n", s.action, s.name,
                             s.cv_rmse_before, s.cv_rmse_after, unit,
                             std::isfinite(s.cv_shape_rmse_before)
                                 ? fmt::format(", of the runs' shape {:.4g} -> {:.4g} {}", s.cv_shape_rmse_before, s.cv_shape_rmse_after, unit)
                                 : "",
                             s.gain_percent, s.criterion);
}

void print(const FrictionDiagnosis& d) {
  std::cout << fmt::format("baseline: residual RMSE {:.3f} N, Durbin-Watson {:.2f}; residuals against covariates:\n",
                           d.baseline.rmse_N, d.baseline.durbin_watson);
  print_covariates(d.baseline.covariates, "N");
  print_lack_of_fit(d.baseline.lack_of_fit, "N");
  print_rounds(d.rounds, "N");
  for (const auto& note : d.design_notes) std::cout << "design: " << note << "\n";
  print_empirical(d.empirical, "N");
  print_steps(d.steps, "N");
  std::cout << "verdict: " << d.verdict << "\n  " << d.summary << "\n";
}

struct DiagnoseThermalOptions {
  std::string manifest;
  std::string catalog_file;
  std::string name = "thermal_diagnosis";
  std::string output_dir = "fits";
  ThermalModelOptions model;
  ThermalDiagnosisOptions diagnosis;
};

void print(const ThermalDiagnosis& d) {
  std::cout << fmt::format("baseline: alpha {:.4f}, residual RMSE {:.4f} K, lag-1 autocorrelation {:.3f} (n_eff {:.0f}); "
                           "residuals against covariates:\n",
                           d.baseline_fit.joint.parameter("alpha").value, d.baseline.rmse_K, d.baseline.lag1_autocorrelation,
                           d.baseline.n_eff);
  print_covariates(d.baseline.covariates, "K");
  print_lack_of_fit(d.baseline.lack_of_fit, "K");
  for (const auto& s : d.skipped) std::cout << "not tried: " << s << "\n";
  print_rounds(d.rounds, "K");
  print_empirical(d.empirical, "K");
  print_steps(d.steps, "K");
  std::cout << "verdict: " << d.verdict << "\n  " << d.summary << "\n";
}

void run_diagnose_thermal(DiagnoseThermalOptions& o, const std::vector<std::string>& argv) {
  require_writable_output(o.output_dir);
  std::vector<std::pair<std::string, std::string>> inputs;
  o.model.apply(o.diagnosis.fit, inputs);
  const std::optional<GuideCatalog> catalog = user_catalog(o.catalog_file);
  const ThermalDataSet data = load_thermal_dataset(o.manifest, catalog ? &*catalog : nullptr, input_scope());
  inputs.emplace_back(o.manifest, sha256_file(o.manifest));
  for (const auto& run : data.runs) inputs.emplace_back(run.file.string(), sha256_file(run.file));
  const ThermalDiagnosis d = with_progress("thermal diagnosis", [&](const Progress& progress) {
    o.diagnosis.progress = progress;
    return diagnose_thermal(data, o.diagnosis);
  });
  const auto file = std::filesystem::path(o.output_dir) / (o.name + ".json");
  write_file_atomically(file, with_output_record(thermal_diagnosis_json(d), argv, &inputs, &output_mode().options));
  offer_machine_output(file, true);
  print(d);
  std::cout << "wrote " << file.string() << "\n";
}

void run_diagnose_friction(DiagnoseFrictionOptions& o, const std::vector<std::string>& argv) {
  require_writable_output(o.output_dir);
  apply_friction_constant_options(o.constants, o.diagnosis.fit);
  const FrictionInput input = load_friction_input(o.files, o.input);
  const FrictionLog& log = input.log;
  const FrictionDiagnosis d = with_progress("friction diagnosis", [&](const Progress& progress) {
    o.diagnosis.progress = progress;
    return diagnose_friction(log, o.diagnosis);
  });
  const auto file = std::filesystem::path(o.output_dir) / (o.name + ".json");
  write_file_atomically(file, with_output_record(friction_diagnosis_json(d), argv, &input.inputs, &output_mode().options));
  offer_machine_output(file, true);
  print(d);
  std::cout << "wrote " << file.string() << "\n";
}

}  // namespace

void setup_diagnose(CLI::App& app, const std::vector<std::string>& argv) {
  CLI::App* diagnose = app.add_subcommand("diagnose", "Find what the model gets wrong and why");
  diagnose->require_subcommand(1);
  auto o = std::make_shared<DiagnoseFrictionOptions>();
  CLI::App* friction = diagnose->add_subcommand("friction", "Friction law against load-cell logs");
  friction->add_option("files", o->files, "Friction log CSV files, or one friction manifest (.toml)")->required();
  o->input.add_to(*friction);
  friction->add_option("--name", o->name, "Name of the output")->capture_default_str();
  friction->add_option("-o,--output-dir", o->output_dir, "Output folder")->capture_default_str();
  friction->add_option("--min-gain", o->diagnosis.min_cv_gain_percent, "Least held-out RMSE gain to accept a cause, %")
      ->check(at_least(0))
      ->capture_default_str();
  friction->add_option("--lrt-p", o->diagnosis.lrt_p, "Significance level of the likelihood-ratio test")
      ->check(inside(0, 1))
      ->capture_default_str();
  add_friction_constant_options(*friction, o->constants);
  friction->callback([o, &argv] { run_diagnose_friction(*o, argv); });

  auto t = std::make_shared<DiagnoseThermalOptions>();
  CLI::App* thermal = diagnose->add_subcommand("thermal", "Rail model against thermocouple traces");
  thermal->add_option("manifest", t->manifest, "Thermal data set manifest (TOML)")->required();
  thermal->add_option("--catalog", t->catalog_file,
                      kCatalogHelp);
  thermal->add_option("--name", t->name, "Name of the output")->capture_default_str();
  thermal->add_option("-o,--output-dir", t->output_dir, "Output folder")->capture_default_str();
  t->model.add_to(*thermal, t->diagnosis.fit);
  t->model.add_friction_file(*thermal);
  thermal->add_option("--min-gain", t->diagnosis.min_cv_gain_percent, "Least held-out RMSE gain to accept a cause, %")
      ->check(at_least(0))
      ->capture_default_str();
  thermal->add_option("--lrt-p", t->diagnosis.lrt_p, "Significance level of the likelihood-ratio test")
      ->check(inside(0, 1))
      ->capture_default_str();
  thermal->callback([t, &argv] { run_diagnose_thermal(*t, argv); });
}

}  // namespace lmcal::cli
