// SHA-256 of an input file (OpenSSL), recorded in every fit so a result names the exact
// bytes it came from.
#pragma once

#include "lmcal/export.hpp"

#include <filesystem>
#include <string>
#include <string_view>

namespace LMCAL_API lmcal {

// Lower-case hex digest; InputError if the file cannot be read.
std::string sha256_file(const std::filesystem::path& file);
// Of a text (the options a fleet's outputs depend on).
std::string sha256_text(std::string_view text);

}  // namespace lmcal
