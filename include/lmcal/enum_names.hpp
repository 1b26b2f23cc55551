// An options enum's names, spelt once: its public header lists its values in order
// (`inline constexpr RunOffsets kRunOffsets[] = {…}`) beside its `to_string`, and its
// `parse_*` and every front end (the CLI's choices and completions, the Python keywords, the
// outputs) go through these helpers, so no name is typed twice (ceres types.h: one
// XToString / StringToX pair per enum).
//
// Example:
//   RunOffsets parse_run_offsets(std::string_view name, const std::string& parameter = "run_offsets") {
//     return parse_enum(kRunOffsets, name, parameter, "model");
//   }
//   parse_run_offsets("sometimes", "--run-offsets");
//   // InvalidParameter "--run-offsets: unknown model 'sometimes'; expected auto, none, fixed or random"
//
// Trap: the names are to_string's, found by argument-dependent lookup: declare to_string
// before the first parse_enum of the enum.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "lmcal/error.hpp"

namespace lmcal {

// The names of `values` as to_string spells them, in their order (CLI completions, help).
template <typename Enum, std::size_t N>
std::vector<std::string> enum_names(const Enum (&values)[N]) {
  std::vector<std::string> names;
  for (const Enum v : values) names.emplace_back(to_string(v));
  return names;
}

// "a, b or c": the accepted names, for a message.
template <typename Enum, std::size_t N>
std::string expected_names(const Enum (&values)[N]) {
  std::string list;
  for (std::size_t i = 0; i < N; ++i) list += (i == 0 ? "" : i + 1 == N ? " or " : ", ") + std::string(to_string(values[i]));
  return list;
}

// The value whose to_string is `name`; otherwise InvalidParameter(parameter,
// "unknown <what> '<name>'; expected a, b or c").
template <typename Enum, std::size_t N>
Enum parse_enum(const Enum (&values)[N], std::string_view name, const std::string& parameter, std::string_view what) {
  for (const Enum v : values)
    if (name == to_string(v)) return v;
  throw InvalidParameter(parameter, "unknown " + std::string(what) + " '" + std::string(name) + "'; expected " + expected_names(values));
}

}  // namespace lmcal
