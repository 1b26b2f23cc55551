#include "output_mode.hpp"

#include "terminal.hpp"

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

namespace {

// A name given, or its value as given (a list joined by commas; a flag's count), else its default.
std::string resolved_value(const CLI::Option& option) {
  if (option.count() == 0) return option.get_default_str();
  if (option.get_type_size() == 0) return std::to_string(option.count());
  std::string value;
  for (const std::string& r : option.results()) value += (value.empty() ? "" : ",") + r;
  return value;
}

// The options of `command` and of its option groups (unnamed sub-apps).
void collect_options(const CLI::App& command, std::vector<std::pair<std::string, std::string>>& out) {
  for (const CLI::Option* option : command.get_options()) {
    const std::string name = option->get_name();  // the long name, or a positional's
    if (name.empty() || name == "--help") continue;
    out.emplace_back(name.substr(name.find_first_not_of('-')), resolved_value(*option));
  }
  for (const CLI::App* group : command.get_subcommands([](const CLI::App* a) { return a->get_name().empty(); }))
    collect_options(*group, out);
}

}  // namespace

void record_resolved_options(const CLI::App& app) {
  const CLI::App* command = &app;
  for (bool deeper = true; deeper;) {
    deeper = false;
    for (const CLI::App* used : command->get_subcommands())
      if (!used->get_name().empty()) {
        command = used;
        deeper = true;
        break;
      }
  }
  if (command == &app) return;
  output_mode().options.clear();
  collect_options(*command, output_mode().options);
}

StdoutGate::StdoutGate(bool wrap) : saved_(std::cout.rdbuf()) {
  const OutputMode& m = output_mode();
  if (m.json || m.verbosity == Verbosity::quiet) {
    std::cout.rdbuf(nullptr);  // writes fail silently
  } else if (const std::size_t width = wrap ? stdout_columns() : 0; width > 0) {
    wrapping_ = std::make_unique<WrappingBuffer>(saved_, width);
    std::cout.rdbuf(wrapping_.get());
  }
}

StdoutGate::~StdoutGate() {
  std::cout.rdbuf(saved_);
  std::cout.clear();
  wrapping_.reset();  // its last line, if it had no newline
}

bool StdoutGate::print_machine_output() {
  std::cout.rdbuf(saved_);
  std::cout.clear();
  wrapping_.reset();
  const OutputMode& m = output_mode();
  if (m.machine_output.empty()) return false;
  std::ifstream in(m.machine_output, std::ios::binary);
  std::cout << in.rdbuf();
  return true;
}

}  // namespace lmcal::cli
