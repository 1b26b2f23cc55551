// What the command line says when it cannot run, and with which exit status:
//
//   0  done
//   1  input refused: a file, a value in it, or an option's value (lmcal::InputError,
//      lmcal::InvalidParameter): "lmcal: error: FILE:LINE:COLUMN: what was expected"
//   2  usage: an unknown command or option (with the nearest known one: "unknown command
//      'calibrat'; did you mean 'calibrate'?"), a missing or malformed argument
//   3  an internal failure (a bug: please report it with the command)
//   4  a fit that gives no usable answer (nothing written unless --keep-unusable)
//
// Every message starts with "lmcal: error:" on stderr.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <string_view>
#include <vector>

namespace lmcal::cli {

inline constexpr int kExitInput = 1, kExitUsage = 2, kExitInternal = 3, kExitUnusable = 4;

// The known names nearest to `given` (at most 3): those it begins, else those at the least edit
// distance within a third of its length (at least 2); none when nothing is near.
std::vector<std::string> nearest(std::string_view given, const std::vector<std::string>& known);

// Prints the usage error for `e` (help and version requests print as CLI11 does) and returns
// the exit status. `args` as main received them.
int report_parse_error(CLI::App& app, const CLI::ParseError& e, const std::vector<std::string>& args);

}  // namespace lmcal::cli
