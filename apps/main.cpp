// lmcal: calibration toolkit for roller linear-motion guideways.
#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <glog/logging.h>

#include <iostream>
#include <optional>

#include "cli_common.hpp"
#include "output_mode.hpp"
#include "usage.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/config_file.hpp"
#include "lmcal/process.hpp"
#include "lmcal/version.hpp"

namespace {

// The --config file, checked before CLI11 reads it (it would read /dev/zero until memory ran out,
// and merge two [calibrate] tables without a word).
void check_config_files(const std::vector<std::string>& args) {
  for (std::size_t i = 1; i < args.size() && args[i] != "--"; ++i) {
    if (args[i] == "--config" && i + 1 < args.size()) lmcal::io::check_config_file(args[i + 1]);
    else if (args[i].starts_with("--config=")) lmcal::io::check_config_file(args[i].substr(std::string_view("--config=").size()));
  }
}

}  // namespace

int main(int argc, char** argv) {
  // As outputs record it: "lmcal …", not where the binary happens to be.
  std::vector<std::string> args(argv, argv + argc);
  if (!args.empty()) args[0] = "lmcal";
  // Ceres logs through glog; lmcal reports numerical trouble in its results instead.
  FLAGS_minloglevel = google::GLOG_FATAL;
  lmcal::keep_freed_memory();  // one job, then exit: pages freed are reused, not faulted in again
  CLI::App app{"lmcal: calibrate the friction and thermal models of roller LM guides (Cheng et al. 2017)"};
  std::string version = fmt::format("lmcal {} (commit {})\n", LMCAL_VERSION, lmcal::git_commit());
  for (const auto& [name, v] : lmcal::software_versions())
    if (name != "lmcal") version += fmt::format("  {:<14} {}\n", name, v);
  version.pop_back();
  app.set_version_flag("--version", version, "Print lmcal's version, commit and libraries, and exit");
  app.formatter(std::make_shared<lmcal::cli::HelpFormatter>());  // before the subcommands: they copy it
  app.set_config("--config", "", "Read options from a TOML file");
  app.allow_config_extras(CLI::config_extras_mode::error);  // a misspelt key is refused, as in a manifest
  app.fallthrough();  // the global options work after the command too: lmcal fit friction LOG --json
  lmcal::cli::OutputMode& mode = lmcal::cli::output_mode();
  app.add_flag_function("-q,--quiet", [&mode](std::int64_t) { mode.verbosity = lmcal::cli::Verbosity::quiet; },
                        "Errors only: no summary, no progress");
  app.add_flag_function("-v,--verbose", [&mode](std::int64_t) { mode.verbosity = lmcal::cli::Verbosity::verbose; },
                        "Progress as lines even in a pipe or a log, and each step's wall time");
  app.add_flag("--allow-outside-root", lmcal::cli::input_scope().allow_outside,
               "Read the files manifests, duty files and fleet.toml name even outside their own folder (or the fleet's "
               "ROOT); refused by default, so that a folder someone else wrote cannot make lmcal read other files");
  app.add_flag("--json", mode.json, "Print the command's main JSON output (calibration.json, friction.json, …) on stdout "
                                    "instead of the summary");
  // After the options, before the command runs: stdout silenced for -q and --json, else its
  // prose wrapped to the terminal (not the man page's roff nor the completion script).
  std::optional<lmcal::cli::StdoutGate> gate;
  app.parse_complete_callback([&gate, &app] {
    lmcal::cli::record_resolved_options(app);
    gate.emplace(!app.got_subcommand("man") && !app.got_subcommand("completion"));
  });
  app.require_subcommand(1);
  lmcal::cli::setup_simulate(app, args);
  lmcal::cli::setup_generate(app, args);
  lmcal::cli::setup_check(app);
  lmcal::cli::setup_fit(app, args);
  lmcal::cli::setup_diagnose(app, args);
  lmcal::cli::setup_calibrate(app);
  lmcal::cli::setup_fleet(app);
  lmcal::cli::setup_predict(app, args);
  lmcal::cli::setup_plan(app, args);
  lmcal::cli::setup_completion(app);
  try {
    check_config_files(args);
    app.parse(argc, argv);
    if (mode.json && gate && !gate->print_machine_output()) {
      std::cerr << "lmcal: error: --json: this command writes no JSON output\n";
      return lmcal::cli::kExitUsage;
    }
  } catch (const CLI::ParseError& e) {
    return lmcal::cli::report_parse_error(app, e, args);
  } catch (const lmcal::cli::UnusableFit& e) {
    std::cerr << "lmcal: error: " << e.what() << "\n";
    return lmcal::cli::kExitUnusable;
  } catch (const lmcal::InputError& e) {
    std::cerr << "lmcal: error: " << e.what() << "\n";
    return lmcal::cli::kExitInput;
  } catch (const lmcal::InvalidParameter& e) {
    std::cerr << "lmcal: error: " << e.what() << "\n";
    return lmcal::cli::kExitInput;
  } catch (const std::bad_alloc&) {  // a size within the limits that still did not fit this machine
    std::cerr << "lmcal: error: out of memory: the inputs or options ask for more than this machine has "
                 "(docs/formats.md#limits lists what each size costs)\n";
    return lmcal::cli::kExitInput;
  } catch (const std::filesystem::filesystem_error& e) {  // the system refused a file or folder: not lmcal's fault
    std::cerr << "lmcal: error: " << lmcal::cli::filesystem_message(e) << "\n";
    return lmcal::cli::kExitInput;
  } catch (const std::exception& e) {
    std::cerr << "lmcal: error: internal failure, please report it with the command: " << e.what() << "\n";
    return lmcal::cli::kExitInternal;
  }
  return 0;
}
