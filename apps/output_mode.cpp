#include "output_mode.hpp"

#include <fstream>
#include <iostream>

namespace lmcal::cli {

namespace {
bool machine_output_is_main = false;
}

OutputMode& output_mode() {
  static OutputMode mode;
  return mode;
}

void offer_machine_output(const std::filesystem::path& file, bool main) {
  OutputMode& m = output_mode();
  if (machine_output_is_main && !main) return;
  if (main || m.machine_output.empty()) m.machine_output = file;
  machine_output_is_main = machine_output_is_main || main;
}

StdoutGate::StdoutGate() : saved_(std::cout.rdbuf()) {
  const OutputMode& m = output_mode();
  if (m.json || m.verbosity == Verbosity::quiet) std::cout.rdbuf(nullptr);  // writes fail silently
}

StdoutGate::~StdoutGate() {
  std::cout.rdbuf(saved_);
  std::cout.clear();
}

bool StdoutGate::print_machine_output() {
  std::cout.rdbuf(saved_);
  std::cout.clear();
  const OutputMode& m = output_mode();
  if (m.machine_output.empty()) return false;
  std::ifstream in(m.machine_output, std::ios::binary);
  std::cout << in.rdbuf();
  return true;
}

}  // namespace lmcal::cli
