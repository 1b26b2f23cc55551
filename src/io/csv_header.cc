// The CSV header bound to a loader's columns: names with units, the known columns matched,
// the ignored ones checked for a near miss, and the errors that name a cell.
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cctype>
#include <map>

#include "io/csv_reader.hpp"
#include "lmcal/error.hpp"

namespace lmcal::csv {

namespace {

namespace fs = std::filesystem;

// "tc12" is a member of the family "tc"; "tcx" and "tc_1" are not.
bool is_family_member(std::string_view base, std::string_view prefix) {
  return base.starts_with(prefix) && std::all_of(base.begin() + static_cast<std::ptrdiff_t>(prefix.size()), base.end(),
                                                 [](char c) { return c >= '0' && c <= '9'; });
}

}  // namespace

// ---- Names with units ---------------------------------------------------------------------

UnitMatch match_unit(std::string_view name, std::string_view base, Quantity quantity) {
  if (!name.starts_with(base)) return {};
  if (name.size() == base.size()) return {UnitMatch::no_unit, {}, {}};
  if (name[base.size()] != '_') return {};  // "loads_N" is not "load"
  if (auto split = split_unit(name, quantity)) {
    // "load_cell_N" is a force, but not the load: some other column.
    if (split->name != base) return {};
    return {UnitMatch::match, std::move(*split), {}};
  }
  return {UnitMatch::unknown_unit, {}, std::string(name.substr(base.size() + 1))};
}

std::string accepted_names(std::string_view base, Quantity quantity) {
  std::vector<std::string> names;
  for (const std::string& unit : unit_names(quantity)) names.push_back(fmt::format("{}_{}", base, unit));
  return fmt::format("{}", fmt::join(names, ", "));
}

std::string canonical_name(std::string_view base, Quantity quantity) {
  return fmt::format("{}_{}", base, unit_names(quantity).front());
}

// ---- Header binding -----------------------------------------------------------------------

namespace {

// The spec a header cell belongs to, with its base name and unit; nullopt for a column the
// loader does not know. Throws for a known column without a unit or with an unknown one.
// Several specs may share a name in different quantities (a linear and an angular velocity):
// the header matches any of them, and is refused only when it matches none.
std::optional<Column> classify(const Reader& reader, std::size_t cell, std::span<const ColumnSpec> specs) {
  const std::string& header = reader.header()[cell];
  std::optional<std::pair<std::size_t, UnitMatch>> problem;  // the first spec whose name it carries
  for (std::size_t s = 0; s < specs.size(); ++s) {
    const ColumnSpec& spec = specs[s];
    Column column{.spec = s,
                  .cell = cell,
                  .header = header,
                  .name = std::string(spec.name),
                  .rule = spec.rule,
                  .hint = spec.hint,
                  .range = spec.quantity ? std::optional(physical_range(*spec.quantity)) : spec.range};
    if (!spec.quantity) {
      if (header == spec.name) return column;
      continue;
    }
    // A family member's base is everything before the unit ("tc12" in "tc12_K").
    const std::string_view base = spec.family ? std::string_view(header).substr(0, header.find('_')) : spec.name;
    if (spec.family && !is_family_member(base, spec.name)) continue;
    UnitMatch m = match_unit(header, base, *spec.quantity);
    switch (m.kind) {
      case UnitMatch::other: continue;
      case UnitMatch::no_unit:
      case UnitMatch::unknown_unit:
        if (!problem) problem.emplace(s, std::move(m));
        continue;
      case UnitMatch::match:
        column.name = m.split.name;
        column.conversion = m.split.conversion;
        return column;
    }
  }
  if (!problem) return std::nullopt;
  // Every unit of every spec of that name.
  const ColumnSpec& first = specs[problem->first];
  const std::string_view base = first.family ? std::string_view(header).substr(0, header.find('_')) : first.name;
  std::vector<std::string> accepted;
  for (const ColumnSpec& spec : specs)
    if (spec.quantity && spec.name == first.name) accepted.push_back(accepted_names(base, *spec.quantity));
  const std::string names = fmt::format("{}", fmt::join(accepted, ", "));
  if (problem->second.kind == UnitMatch::no_unit)
    reader.fail(cell, fmt::format("column '{}' has no unit; accepted: {}", header, names));
  reader.fail(cell, fmt::format("column '{}': unknown unit '{}'; accepted: {}", header, problem->second.unit, names));
}

std::string lowercase(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// Edit distance with adjacent transpositions (optimal string alignment: "frcition" is one
// from "friction"), for short header names.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] != b[j - 1])});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

// Short names rigs use for lmcal's columns.
std::string_view alias_of(std::string_view name) {
  static constexpr std::pair<std::string_view, std::string_view> kAliases[] = {
      {"dir", "direction"},   {"sense", "direction"}, {"temp", "temperature"}, {"speed", "velocity"},
      {"vel", "velocity"},    {"v", "velocity"},      {"f", "friction"},
      {"t", "time"},          {"amb", "ambient"},     {"thermocouple", "tc"},  {"pos", "position"},
      {"nu40", "viscosity40"}, {"visc", "viscosity40"}};
  for (const auto& [alias, known] : kAliases)
    if (name == alias) return known;
  return {};
}

// The known column an ignored header looks like (different case, a short alias, one letter
// off), as the name to write instead; nullopt when it resembles none. The name is compared
// without its unit, so that "load_cell_N" (another force) does not look like "load_N".
std::optional<std::string> resemblance(std::string_view header, std::span<const ColumnSpec> specs) {
  for (const ColumnSpec& spec : specs) {
    std::string name(header), unit;
    if (spec.quantity)
      if (auto split = split_unit(header, *spec.quantity)) {
        name = split->name;
        unit = split->unit;
      }
    const std::string lower = lowercase(name);
    const std::string_view known = spec.name;
    const bool member = spec.family && is_family_member(lower, known);
    const bool alike = lower == known || member || alias_of(lower) == known ||
                       (known.size() >= 4 && edit_distance(lower, known) <= 1);
    if (!alike) continue;
    if (!spec.quantity) return std::string(known);
    const std::string base = member ? lower : spec.family ? fmt::format("{}1", known) : std::string(known);
    return unit.empty() ? canonical_name(base, *spec.quantity) : fmt::format("{}_{}", base, unit);  // the user's unit
  }
  return std::nullopt;
}

bool is_timestamp_name(std::string_view header) {
  const std::string lower = lowercase(header);
  return lower.find("timestamp") != std::string::npos || lower == "date" || lower == "datetime" ||
         lower == "date_time" || lower == "clock" || lower == "time_of_day";
}

}  // namespace

std::vector<Column> bind_header(const Reader& reader, std::span<const ColumnSpec> specs, LoadReport& report) {
  std::vector<Column> columns;
  std::map<std::string, std::string> seen;  // base name -> header (one column per name, whatever its unit or quantity)
  for (std::size_t cell = 0; cell < reader.header().size(); ++cell) {
    std::optional<Column> column = classify(reader, cell, specs);
    if (!column) {
      const std::string& header = reader.header()[cell];
      report.ignored_columns.push_back(header);
      if (is_timestamp_name(header)) {
        report.warnings.push_back(fmt::format("column '{}' (a timestamp?) is ignored: lmcal reads time from a time_s column "
                                              "(or time_ms, time_min, time_h) holding seconds since the start; convert it",
                                              header));
      } else if (auto known = resemblance(header, specs)) {
        report.warnings.push_back(fmt::format("column '{}' is ignored, but looks like '{}' (names are case-sensitive and "
                                              "carry their unit): rename it if that is what it holds",
                                              header, *known));
      }
      continue;
    }
    const auto [it, inserted] = seen.emplace(column->name, column->header);
    if (!inserted) {
      reader.fail(
          cell, fmt::format("duplicate column '{}': '{}' already gives {}", column->header, it->second, column->name));
    }
    if (const auto& quantity = specs[column->spec].quantity) {
      const std::string unit = column->header.substr(column->name.size() + 1);
      const std::string& internal = unit_names(*quantity).front();
      if (unit != internal) report.conversions[column->header] = fmt::format("{} -> {}", unit, internal);
    }
    columns.push_back(std::move(*column));
  }

  for (std::size_t s = 0; s < specs.size(); ++s) {
    if (specs[s].required && !find_column(columns, s)) reader.fail_at(reader.header_line(), 1, missing_column(specs[s]));
  }
  return columns;
}

void fail_at_cell(const fs::path& file, long line, std::size_t cell, const std::string& what) {
  Reader reader(file);
  if (reader.seek_line(line)) reader.fail(cell, what);
  throw InputError(reader.file(), line, 0, what);
}

std::string missing_column(const ColumnSpec& spec) {
  if (!spec.quantity) return fmt::format("missing column '{}'", spec.name);
  if (spec.family) {
    return fmt::format("missing column '{}': expected one or more {}<n> columns (accepted units: {})",
                       canonical_name(fmt::format("{}1", spec.name), *spec.quantity), spec.name,
                       fmt::join(unit_names(*spec.quantity), ", "));
  }
  return fmt::format("missing column '{}' (accepted units: {})", canonical_name(spec.name, *spec.quantity),
                     accepted_names(spec.name, *spec.quantity));
}

const Column* find_column(const std::vector<Column>& columns, std::size_t spec) {
  const auto it = std::find_if(columns.begin(), columns.end(), [&](const Column& c) { return c.spec == spec; });
  return it == columns.end() ? nullptr : &*it;
}

}  // namespace lmcal::csv

