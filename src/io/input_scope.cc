#include "lmcal/io/input_scope.hpp"

#include <fmt/format.h>

#include "io/input_file.hpp"

namespace lmcal {

namespace fs = std::filesystem;

namespace {

// The lexical (`..` applied) or real (symlinks followed) absolute form of `p`; empty on failure.
fs::path absolute_form(const fs::path& p, bool real, std::error_code& ec) {
  const fs::path a = fs::absolute(p.empty() ? fs::path(".") : p, ec);
  if (ec) return {};
  return real ? fs::weakly_canonical(a, ec) : a.lexically_normal();
}

bool contains(const fs::path& root, const fs::path& path) {
  const fs::path rel = path.lexically_relative(root);
  return !rel.empty() && *rel.begin() != "..";
}

}  // namespace

std::optional<std::string> outside_scope(const fs::path& path, const fs::path& folder, const InputScope& scope) {
  if (scope.allow_outside) return std::nullopt;
  const fs::path root = scope.root_for(folder);
  const std::string root_name = io::printable((root.empty() ? fs::path(".") : root).string());
  std::error_code ec;
  const fs::path real_root = absolute_form(root, true, ec);
  const fs::path real_path = ec ? fs::path() : absolute_form(path, true, ec);
  if (ec) return fmt::format("cannot be resolved inside {} ({})", root_name, ec.message());
  if (contains(real_root, real_path)) return std::nullopt;
  const bool lexically_inside = contains(absolute_form(root, false, ec), absolute_form(path, false, ec)) && !ec;
  return fmt::format("is outside {}{}: lmcal reads only files inside it (pass --allow-outside-root to read others)",
                     root_name, lexically_inside ? " through a symbolic link" : "");
}

}  // namespace lmcal
