// Helpers shared by the subcommands: value lists on the command line, CSV text,
// and the record of a run's inputs.
#pragma once

#include <nlohmann/json.hpp>

#include "lmcal/io/csv_writer.hpp"
#include "lmcal/io/input_scope.hpp"

#include <filesystem>
#include <cctype>
#include <map>
#include <string>
#include "lmcal/fit/friction_fit.hpp"
#include <string_view>
#include <vector>

namespace lmcal::cli {

// "0.066,0.083,0.11" or "start:stop:step" (inclusive, e.g. "0.01:0.2:0.01"), or a mix
// joined by commas. Throws InvalidParameter naming the option and what was expected.
std::vector<double> parse_list(std::string_view option, std::string_view text);

// "t:T,t:T,..." pairs of time (s) and temperature (°C), for an ambient trace.
std::vector<std::pair<double, double>> parse_pairs(std::string_view option, std::string_view text);

// Writes `files` (name -> contents) into `dir`, all or none (OutputSet), and removes there the
// `replaced` names that are not among them (an earlier run's outputs this one does not
// write); returns the paths written, for the message: "fits/a.json, fits/a_samples.csv and
// fits/a_conditions.csv".
std::string write_outputs(const std::filesystem::path& dir, std::vector<std::pair<std::string, std::string>> files,
                          const std::vector<std::string>& replaced = {});

// "1 run", "3 runs".
std::string plural(std::size_t n, std::string_view noun);

// Where every command's loaders may read the files that manifests, duty files and fleet.toml
// name: inside their own folder, or anywhere with the global flag --allow-outside-root.
InputScope& input_scope();

// "PATH: reason" for a file system error (printable paths, without the library's prefix).
std::string filesystem_message(const std::filesystem::filesystem_error& e);

// Refuses (InvalidParameter naming -o) an output folder, or the folder of an output file, that lmcal could not
// write into (not a folder, read-only, nearly full), before the command computes anything.
void require_writable_output(const std::filesystem::path& folder);

// Version, command line and time-independent facts every output carries alongside.
nlohmann::json run_record(const std::vector<std::string>& argv);


}  // namespace lmcal::cli

#include <functional>
#include <map>
#include <optional>
#include <stdexcept>

#include <CLI/CLI.hpp>

#include "lmcal/io/catalog.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/fit/model_file.hpp"
#include "lmcal/fit/thermal_fit.hpp"
#include "lmcal/models/friction.hpp"

namespace lmcal::cli {

// A fit that gives no answer to use (SolverReport::usable false): its own exit status
// (kExitUnusable), nothing written, unless the user asked to keep it.
class UnusableFit : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// --keep-unusable, on every command that fits.
void add_keep_unusable(CLI::App& app, bool& keep);
// Throws UnusableFit for `why` (what is not usable, and the reason) unless `keep`; with `keep`
// a warning on stderr. Call it before writing the outputs.
void require_usable(const std::optional<std::string>& why, bool keep);

// The help of every --catalog option.
inline constexpr const char* kSkipLinesHelp =
    "Lines before the column names (a logger's preamble) to skip, whatever they hold; errors name the file's lines";
inline constexpr const char* kCatalogHelp =
    "Your guide catalog (TOML: [[guide]] and [[bar]] tables), searched before the built-in one (and instead of a "
    "manifest's catalog)";

// --guide, --catalog and --set FIELD=VALUE overrides of catalog values.
struct GuideOptions {
  std::vector<std::string> guides{"SRN 35C"};
  std::string catalog_file;                 // empty: the built-in catalog
  std::map<std::string, double> overrides;  // e.g. conductivity_W_mK -> 36
  void add_to(CLI::App& app);
  // The catalog entry of `model` with the overrides applied.
  GuideSpec resolve(const std::string& model) const;
  nlohmann::json record() const;
};

// --model FILE: the calibrated model `lmcal calibrate` writes (model.toml), in place of the
// options it gives ("calibrate once, use everywhere").
struct ModelOptions {
  std::string file;  // empty: no model
  void add_to(CLI::App& app, const char* help);
};

// A model file as read, with its SHA-256.
struct LoadedModel {
  std::string file, sha256;
  ModelFile model;
  // Reads --model FILE, which must hold the table the command uses ("friction" or "thermal");
  // none without --model. InputError naming the file and what was expected otherwise.
  static std::optional<LoadedModel> read(const ModelOptions& options, const char* table);
  // Refuses `given` (options the user gave that the model gives, `what`), naming them and --model.
  void refuse(const std::vector<std::string>& given, const std::string& what) const;
  // "inputs" (the file with its SHA-256) and "model" (also the model's provenance: set, lmcal
  // version, command, its inputs) of a run's record.
  void record_into(nlohmann::json& record) const;
};

// The names of those of `options` the user gave (on the command line or in --config).
std::vector<std::string> given(const std::vector<const CLI::Option*>& options);

// The friction law a command simulates: constants and effects.
struct FrictionLaw {
  FrictionConstants<double> constants = paper_friction_constants();
  FrictionEffects<double> effects;        // neutral: the published law
  std::vector<std::string> effect_names;  // the effects in use (a model's causes)
  std::vector<FrictionTerm> terms;        // a model's empirical terms (not named causes)
  // "friction_constants" and "friction_effects" of a run's record.
  void record_into(nlohmann::json& record) const;
  std::string effects_text() const;  // "direction_asymmetry, seal_drag", or "none"
};

// The friction constants, defaulting to the paper's Eq. 8.
struct FrictionOptions {
  FrictionConstants<double> constants = paper_friction_constants();
  void add_to(CLI::App& app);
  // The law: a calibrated model's [friction] (constants and effects) when it has one, refusing
  // a constant option given with it; else these constants, without effects.
  FrictionLaw law(const LoadedModel* model) const;

 private:
  std::vector<const CLI::Option*> options_;  // as added, to tell which the user gave
};

// The rail model's options shared by `fit thermal`, `diagnose thermal` and `calibrate`: heat
// input, source, numerics, and what is held or freed (--alpha-start, --fit-h, --h,
// --fit-initial).
struct ThermalModelOptions {
  std::string friction_fit;  // friction fit JSON for the heat rate (add_friction_file)
  std::string heat = "auto";
  std::string source = "averaged";
  std::string scheme = "crank-nicolson";
  void add_to(CLI::App& app, ThermalFitOptions& fit);
  // --offsets (a diagnosis always fits them).
  static void add_offsets(CLI::App& app, ThermalFitOptions& fit);
  // --friction FILE (not for `calibrate`, whose friction fit is its own).
  void add_friction_file(CLI::App& app);
  // Parses the names into `fit`, reads the friction fit; its file goes to `inputs` with its hash.
  void apply(ThermalFitOptions& fit, std::vector<std::pair<std::string, std::string>>& inputs) const;
  // Copies into `to` the numeric settings of `from` the user gave (a diagnosis keeps its own
  // defaults, e.g. its coarser time step, for the others).
  void copy_given(const ThermalFitOptions& from, ThermalFitOptions& to) const;

 private:
  std::vector<std::pair<const CLI::Option*, std::function<void(const ThermalFitOptions&, ThermalFitOptions&)>>> numeric_;
};

// A value the catalog may lack, or the user's list: the user's list wins.
std::vector<double> or_catalog(const std::vector<double>& given, const GuideSpec& spec,
                               std::optional<double> GuideSpec::*field, const char* name);

// The subcommands; `argv` is recorded in every output.
void setup_simulate(CLI::App& app, const std::vector<std::string>& argv);
void setup_simulate_friction(CLI::App& parent, const std::vector<std::string>& argv);
void setup_simulate_thermal(CLI::App& parent, const std::vector<std::string>& argv);
void setup_generate(CLI::App& app, const std::vector<std::string>& argv);
void setup_check(CLI::App& app);
void setup_fit(CLI::App& app, const std::vector<std::string>& argv);
void setup_fit_thermal(CLI::App& fit, const std::vector<std::string>& argv);
void setup_diagnose(CLI::App& app, const std::vector<std::string>& argv);
void setup_calibrate(CLI::App& app);
void setup_fleet(CLI::App& app);
void setup_completion(CLI::App& app);
void setup_predict(CLI::App& app, const std::vector<std::string>& argv);
void setup_plan(CLI::App& app, const std::vector<std::string>& argv);

// NAME=VALUE options (repeatable, or comma-separated) collected into `values`.
void add_assignments(CLI::App& app, const char* name, std::map<std::string, double>& values, const char* help);

// --covariance (which covariance the intervals quote: auto, iid, hac, cluster, bootstrap) and
// --bootstrap (cluster-bootstrap replicates, 0: none), into `fit`.
void add_uncertainty_options(CLI::App& app, FitOptions& fit);

// The values an option takes, for the shell completion (completion.cpp): `completes(option,
// {"none", "huber", "cauchy"})` returns the option. add_choice registers its own.
CLI::Option* completes(CLI::Option* option, std::vector<std::string> values);
const std::vector<std::string>* completion_values(const CLI::Option* option);

// An old spelling an option still reads without showing it (`lmcal predict --time-step`, now
// --dt as every command names the time step): `name` (no dashes) is one of the option's long
// names. The help (HelpFormatter), the man page, the completion and "did you mean" leave it out;
// the outputs record the option under its first name.
CLI::Option* hidden_alias(CLI::Option* option, const std::string& name);
// The option's long names without its hidden aliases.
std::vector<std::string> shown_long_names(const CLI::Option* option);
// CLI11's help without the hidden aliases; set on the root app before the subcommands are added
// (they copy it).
class HelpFormatter : public CLI::Formatter {
 public:
  std::string make_option_name(const CLI::Option* option, bool is_positional) const override;
};

// An option that takes one of named values (any case), without CLI11's map dump in its help
// or its errors ("--offsets: 'bogus': expected one of auto, fit, hold"):
// add_choice(app, "--profile", fit.profile, "…", "MODE", {{"auto", …}, …}).
template <typename Enum>
CLI::Option* add_choice(CLI::App& app, const std::string& name, Enum& target, const std::string& help,
                        const std::string& type_name, std::map<std::string, Enum> values) {
  std::string names, current;
  for (const auto& [key, value] : values) {
    names += (names.empty() ? "" : ", ") + key;
    if (value == target) current = key;  // the default, as help and the outputs' options show it
  }
  std::vector<std::string> keys;
  for (const auto& [key, value] : values) keys.push_back(key);
  return completes(app.add_option_function<std::string>(
                name,
                [&target, values, names, name](const std::string& given) {
                  std::string key = given;
                  for (char& c : key) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
                  const auto it = values.find(key);
                  if (it == values.end())
                    throw CLI::ValidationError(name, "'" + given + "': expected one of " + names);
                  target = it->second;
                },
                help),
                   std::move(keys))
      ->type_name(type_name)
      ->default_str(current);
}
// The same with the library's names for the enum (its list of values and their to_string):
// add_choice(app, "--offsets", fit.offsets, "…", "MODE", kThermalOffsets).
template <typename Enum, std::size_t N>
CLI::Option* add_choice(CLI::App& app, const std::string& name, Enum& target, const std::string& help,
                        const std::string& type_name, const Enum (&values)[N]) {
  std::map<std::string, Enum> named;
  for (const Enum value : values) named.emplace(to_string(value), value);
  return add_choice(app, name, target, help, type_name, std::move(named));
}

// The friction constants a command fits, holds and starts from: --free, --fix, --start,
// --bound, --run-offsets (how the load cell's zero moves between runs) and --law-temperature (the
// temperature the law is evaluated at).
struct FrictionConstantOptions {
  std::vector<std::string> free;        // empty: all seven
  std::map<std::string, double> fixed;  // held at these values
  std::map<std::string, double> start;
  std::vector<std::string> bounds;      // NAME=LO:HI
  std::string run_offsets;              // auto, none, fixed, random; empty: the command's default
  std::string temperature;              // logged, block-mean; empty: the command's default
};
void add_friction_constant_options(CLI::App& app, FrictionConstantOptions& o);
// Into `f` (InvalidParameter naming the option for an unknown constant or a bad bound).
void apply_friction_constant_options(const FrictionConstantOptions& o, FrictionFitOptions& f);

// How raw load-cell logs are segmented (--force-sign, --max-acceleration, --settling, ...),
// and --catalog for the guides a manifest names; the friction files a command reads (CSV logs,
// or one friction manifest) loaded with them.
struct FrictionInputOptions {
  RawFrictionOptions raw;
  std::string force_sign = "follows-motion", duplicate_times = "average";
  std::string segmentation = "plateaus";
  std::string force_sensor = "unknown";
  std::string catalog_file;
  void add_to(CLI::App& app);
  // The settings the user gave, by RawFrictionOptions' field names (they win over a manifest's [raw]).
  std::vector<std::string> raw_given() const;
  // `raw` with the names parsed.
  RawFrictionOptions parsed() const;

 private:
  void add_drive_options(CLI::App& app);  // --lead, --pinion-radius, ... into raw.drive
  std::vector<std::pair<const CLI::Option*, std::string>> options_;  // option -> field name
};

// --catalog FILE: the user's catalog, loaded (none without it).
std::optional<GuideCatalog> user_catalog(const std::string& file);

struct FrictionInput {
  FrictionLog log;
  std::vector<std::pair<std::string, std::string>> inputs;  // every file read -> sha256
  RawFrictionOptions raw;                                   // as applied
};
// CSV logs, or one .toml friction manifest (its runs' conditions and its [raw] settings).
FrictionInput load_friction_input(const std::vector<std::string>& files, const FrictionInputOptions& options);
// The same without hashing the files (`inputs` lists them with an empty hash): for `check`,
// which records nothing.
FrictionInput read_friction_input(const std::vector<std::string>& files, const FrictionInputOptions& options);

// Checks of an option's value, with messages like a file value's: "-5 is below 0: expected a
// value of at least 0" (CLI11's own print the type's limits).
CLI::Validator at_least(double low);
CLI::Validator inside(double low, double high);  // exclusive
// Inclusive, `high` a size limit of docs/formats.md#limits: "1e9 is above 1000: expected a value
// from 1 to 1000 (docs/formats.md#limits)".
CLI::Validator up_to_limit(double low, double high);

// A list option parsed with parse_list.
void add_list(CLI::App& app, const char* name, std::vector<double>& values, const char* help);

}  // namespace lmcal::cli
