#include "io/manifest.hpp"

#include <fmt/format.h>

#include <cmath>
#include <utility>

#include "io/csv_reader.hpp"
#include "io/file_kind.hpp"
#include "io/input_file.hpp"
#include "lmcal/error.hpp"
#include "lmcal/io/limits.hpp"

namespace lmcal::manifest {

namespace fs = std::filesystem;

namespace {

bool before(const toml::source_region& a, const toml::source_region& b) {
  return std::pair(a.begin.line, a.begin.column) < std::pair(b.begin.line, b.begin.column);
}

}  // namespace

void Manifest::fail(const toml::source_region& where, const std::string& what) const {
  throw InputError(file, static_cast<long>(where.begin.line), static_cast<long>(where.begin.column), what);
}

toml::table Manifest::parse() const {
  const std::string text = io::read_text_file(file, kind);
  try {
    return toml::parse(text, file);
  } catch (const toml::parse_error& e) {
    const std::string looks = io::looks_like(text);
    if (!looks.empty() && !looks.starts_with("a TOML"))
      throw InputError(file, 0, 0, fmt::format("this looks like {}; expected a TOML {} (key = value lines and tables)", looks, kind));
    fail(e.source(), std::string(e.description()));
  }
}

fs::path Manifest::existing_file(const toml::node& where, const std::string& name) const {
  const fs::path path = folder / name;
  if (auto problem = outside_scope(path, folder, scope)) fail(where.source(), fmt::format("file '{}' {}", name, *problem));
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    fail(where.source(),
         fmt::format("file '{}' not found (looked in {})", name, folder.empty() ? std::string(".") : folder.string()));
  }
  if (auto problem = io::not_a_file(path)) fail(where.source(), fmt::format("file '{}': {}", name, *problem));
  return path;
}

double number_of(const Manifest& m, const toml::key& key, const toml::node& node) {
  std::optional<double> value;
  if (const auto* i = node.as_integer()) value = static_cast<double>(i->get());
  if (const auto* f = node.as_floating_point()) value = f->get();
  if (!value) m.fail(node.source(), fmt::format("expected a number for {}", key.str()));
  if (!std::isfinite(*value)) m.fail(node.source(), fmt::format("expected a finite number for {}", key.str()));
  return *value;
}

double converted_number_of(const Manifest& m, const toml::key& key, const toml::node& node, const Conversion& conversion,
                           const PhysicalRange& range) {
  const double written = number_of(m, key, node);
  const double value = csv::to_internal(conversion, written);
  if (!std::isfinite(value))
    m.fail(node.source(), fmt::format("{} = {}: expected a number that stays finite in internal units", key.str(), written));
  if (!range.contains(value)) m.fail(node.source(), out_of_range_message(key.str(), fmt::format("{}", written), range));
  return value;
}

const std::string& string_of(const Manifest& m, const toml::key& key, const toml::node& node) {
  const auto* s = node.as_string();
  if (!s) m.fail(node.source(), fmt::format("expected a string for {}", key.str()));
  // Every string a manifest gives is a name or a file name that reaches outputs and terminals.
  if (auto problem = io::name_problem(s->get(), key.str() == "description")) m.fail(node.source(), fmt::format("{}: {}", key.str(), *problem));
  return s->get();
}

const toml::table& table_of(const Manifest& m, const toml::node& node, std::string_view where) {
  const auto* t = node.as_table();
  if (!t) m.fail(node.source(), fmt::format("expected a table {}", where));
  return *t;
}

const toml::array& run_tables(const Manifest& m, const toml::node& node) {
  const auto* runs = node.as_array();
  if (!runs || !runs->is_array_of_tables()) m.fail(node.source(), "expected [[run]] tables");
  if (runs->size() > io::kMaxRuns) {
    m.fail((*runs)[io::kMaxRuns].source(),
           fmt::format("more than {} [[run]] tables (the limit, docs/formats.md#limits)", io::kMaxRuns));
  }
  return *runs;
}

std::optional<Conversion> unit_key(const Manifest& m, const toml::key& key, std::string_view base, Quantity quantity) {
  const csv::UnitMatch u = csv::match_unit(key.str(), base, quantity);
  switch (u.kind) {
    case csv::UnitMatch::other: return std::nullopt;
    case csv::UnitMatch::no_unit:
      m.fail(key.source(),
             fmt::format("key '{}' has no unit; accepted: {}", key.str(), csv::accepted_names(base, quantity)));
    case csv::UnitMatch::unknown_unit:
      m.fail(key.source(), fmt::format("key '{}': unknown unit '{}'; accepted: {}", key.str(), u.unit,
                                       csv::accepted_names(base, quantity)));
    case csv::UnitMatch::match: break;
  }
  return u.split.conversion;
}

std::string toml_string(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\n': out += "\\n"; break;
      case '\t': out += "\\t"; break;
      case '\r': out += "\\r"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
          out += fmt::format("\\u{:04X}", static_cast<unsigned char>(c));
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

void remember(const Manifest& m, std::optional<Given>& slot, Given given, std::string_view what) {
  if (slot) {
    const bool later = before(slot->key->source(), given.key->source());
    const Given& first = later ? *slot : given;
    const Given& second = later ? given : *slot;
    m.fail(second.key->source(),
           fmt::format("duplicate key '{}': '{}' already gives {}", second.key->str(), first.key->str(), what));
  }
  slot = given;
}

}  // namespace lmcal::manifest
