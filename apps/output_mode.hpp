// How much the command line says, and in which form (the global options of main.cpp):
//   -q, --quiet     errors only: no summary on stdout, no progress on stderr
//   -v, --verbose   progress as lines on stderr even in a pipe or a log file, and each step's
//                   wall time
//   --json          the command's main JSON output (calibration.json, friction.json,
//                   fleet.json, …) on stdout instead of the summary, for scripts: `lmcal
//                   --json calibrate SET | jq .calibrated_model`
#pragma once

#include <CLI/CLI.hpp>

#include <filesystem>
#include <iosfwd>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace lmcal::cli {

enum class Verbosity { quiet, normal, verbose };

struct OutputMode {
  Verbosity verbosity = Verbosity::normal;
  bool json = false;
  std::filesystem::path machine_output;  // the JSON a command wrote that --json prints
  // The invoked command's options as it runs with them: given (the last value, a list joined
  // by commas; a flag's count), else the default ("" where there is none). Outputs record it.
  std::vector<std::pair<std::string, std::string>> options;
};

// Reads the invoked command's options into output_mode().options, once the line is parsed.
void record_resolved_options(const CLI::App& app);

OutputMode& output_mode();

// Records `file` as the command's JSON output when none better is known: `main` marks the
// one that sums the command up (calibration.json, fleet.json), which later files do not replace.
void offer_machine_output(const std::filesystem::path& file, bool main = false);

// Before the command: silences stdout for -q and --json, else wraps its lines to the terminal
// (`wrap`: not for the man page or the completion script; terminal.hpp says when). After it:
// prints the recorded JSON for --json (an error when the command wrote none), and restores stdout.
class StdoutGate {
 public:
  explicit StdoutGate(bool wrap);
  ~StdoutGate();
  StdoutGate(const StdoutGate&) = delete;
  StdoutGate& operator=(const StdoutGate&) = delete;
  // The JSON for --json; false when the command wrote none.
  bool print_machine_output();

 private:
  std::streambuf* saved_;
  std::unique_ptr<std::streambuf> wrapping_;
};

}  // namespace lmcal::cli
