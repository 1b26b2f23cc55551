#include "usage.hpp"

#include "cli_common.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <cctype>
#include <iostream>
#include <numeric>

namespace lmcal::cli {

namespace {

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  std::iota(row.begin(), row.end(), std::size_t{0});
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

// The deepest subcommand the parser entered ("lmcal generate friction": friction).
CLI::App* deepest(CLI::App* app) {
  for (;;) {
    const auto subs = app->get_subcommands();
    if (subs.empty()) return app;
    app = subs.front();
  }
}

// The named subcommands (option groups are unnamed ones).
std::vector<std::string> subcommand_names(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* s : app.get_subcommands([](const CLI::App*) { return true; }))
    if (!s->get_name().empty()) names.push_back(s->get_name());
  return names;
}

std::vector<std::string> option_names(const CLI::App& app) {
  std::vector<std::string> names;
  for (const CLI::App* a = &app; a; a = a->get_parent())
    for (const CLI::Option* o : a->get_options()) {
      for (const auto& n : shown_long_names(o)) names.push_back("--" + n);
      for (const auto& n : o->get_snames()) names.push_back("-" + n);
    }
  return names;
}

std::string command_path(const CLI::App& app) {
  std::string path;
  for (const CLI::App* a = &app; a; a = a->get_parent()) path = a->get_parent() ? " " + a->get_name() + path : "lmcal" + path;
  return path;
}

// "'calibrat'" with "; did you mean 'calibrate'?" when known names are near.
std::string with_suggestion(const std::string& given, const std::vector<std::string>& known) {
  const std::vector<std::string> near = nearest(given, known);
  if (near.empty()) return fmt::format("'{}'", given);
  return fmt::format("'{}'; did you mean '{}'?", given, fmt::join(near, "' or '"));
}

// The first argument after `app`'s own name that is no option and no known subcommand: what
// the user meant as a command.
std::string unknown_command(const CLI::App& app, const std::vector<std::string>& args) {
  std::size_t at = 1;
  if (app.get_parent()) {  // skip to the subcommand's own name
    const std::vector<std::string> path = [&] {
      std::vector<std::string> p;
      for (const CLI::App* a = &app; a->get_parent(); a = a->get_parent()) p.insert(p.begin(), a->get_name());
      return p;
    }();
    for (const std::string& name : path) {
      while (at < args.size() && args[at] != name) ++at;
      ++at;
    }
  }
  for (; at < args.size(); ++at) {
    if (args[at].starts_with("-")) {
      if (args[at] == "--config") ++at;  // its value
      continue;
    }
    return args[at];
  }
  return "";
}

// CLI11's message for a key of a --config file that names no option.
constexpr const char* kConfigExtra = "INI was not able to parse ";

// "options.toml:3:1: unknown key 'calibrate.alpah'; did you mean 'alpha-start'?"
std::string unknown_config_key(CLI::App& app, const std::string& key) {
  const auto dot = key.rfind('.');
  const std::string section = dot == std::string::npos ? "" : key.substr(0, dot), name = key.substr(dot + 1);
  const CLI::App* where = &app;
  try {
    if (!section.empty()) where = app.get_subcommand(section);
  } catch (const CLI::OptionNotFound&) {
  }
  std::vector<std::string> known;
  for (const CLI::Option* o : where->get_options())
    for (const auto& n : o->get_lnames()) known.push_back(n);
  std::string file = "the --config file", at;
  if (const CLI::Option* config = app.get_config_ptr(); config && config->count() > 0) {
    file = config->as<std::string>();
    std::ifstream in(file);
    std::string line;
    for (long number = 1; std::getline(in, line); ++number) {
      const auto start = line.find_first_not_of(" \t");
      if (start != std::string::npos && line.compare(start, name.size(), name) == 0 &&
          line.find_first_not_of(" \t", start + name.size()) == line.find('=', start)) {
        at = fmt::format(":{}:{}", number, start + 1);
        break;
      }
    }
  }
  std::string message = fmt::format("{}{}: unknown key '{}'", file, at, key);
  std::vector<std::string> near = nearest(name, known);
  for (auto& n : near) n = section.empty() ? n : section + "." + n;
  if (!near.empty()) message += fmt::format("; did you mean '{}'?", fmt::join(near, "' or '"));
  return message;
}

}  // namespace

std::vector<std::string> nearest(std::string_view given, const std::vector<std::string>& known) {
  // Names the given one begins (at 3 characters or more: "--star" for --start and --starts),
  // else those at the least edit distance within a third of its length (at least 2).
  std::vector<std::string> near;
  if (given.size() >= 3)
    for (const std::string& k : known)
      if (k.starts_with(given) && std::find(near.begin(), near.end(), k) == near.end()) near.push_back(k);
  if (!near.empty()) {
    if (near.size() > 3) near.resize(3);
    return near;
  }
  const std::size_t limit = std::max<std::size_t>(2, given.size() / 3);
  std::size_t best = limit;
  for (const std::string& k : known) {
    const std::size_t d = edit_distance(given, k);
    if (d > limit) continue;
    if (d < best) {
      best = d;
      near.clear();
    }
    if (d == best && std::find(near.begin(), near.end(), k) == near.end()) near.push_back(k);
  }
  if (near.size() > 3) near.resize(3);
  return near;
}

int report_parse_error(CLI::App& app, const CLI::ParseError& e, const std::vector<std::string>& args) {
  const std::string kind = e.get_name();
  if (kind == "CallForHelp" || kind == "CallForAllHelp" || kind == "CallForVersion") return app.exit(e);
  CLI::App* where = deepest(&app);
  std::string message = e.what();
  if (dynamic_cast<const CLI::ExtrasError*>(&e)) {
    std::vector<std::string> unknown;
    // With fallthrough (global options after the command) the unknown ones land in a parent.
    std::vector<std::string> extras;
    for (const CLI::App* a = where; a && extras.empty(); a = a->get_parent()) extras = a->remaining(false);
    for (const std::string& a : extras) {
      if (a.starts_with("-")) {
        const std::string name = a.substr(0, a.find('='));
        unknown.push_back("option " + with_suggestion(name, option_names(*where)));
      } else if (subcommand_names(*where).empty()) {
        unknown.push_back(fmt::format("argument '{}'", a));
      } else {
        unknown.push_back("command " + with_suggestion(a, subcommand_names(*where)));
      }
    }
    if (!unknown.empty()) message = "unknown " + unknown.front();  // the first: the others often follow from it
  } else if (kind == "RequiredError" && where->get_require_subcommand_min() > 0 && where->get_subcommands().empty()) {
    const std::string given = unknown_command(*where, args);
    message = given.empty() ? fmt::format("expected a command: {}", fmt::join(subcommand_names(*where), ", "))
                            : "unknown command " + with_suggestion(given, subcommand_names(*where));
  } else if (kind == "ConfigError" && message.starts_with(kConfigExtra)) {
    message = unknown_config_key(app, message.substr(std::string_view(kConfigExtra).size()));
  } else if (kind == "RequiredError") {
    for (const CLI::Option* o : where->get_options())
      if (o->get_required() && o->count() == 0) {
        std::string name = o->get_name(false, true);
        if (o->get_lnames().empty() && o->get_snames().empty())  // a positional: SET
          std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::toupper(c); });
        message = fmt::format("missing {}: {}", name, o->get_description());
        break;
      }
  }
  std::cerr << fmt::format("lmcal: error: {}\nRun '{} --help' for more information.\n", message, command_path(*where));
  return kExitUsage;
}

}  // namespace lmcal::cli
