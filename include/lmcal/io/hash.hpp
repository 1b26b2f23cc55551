// SHA-256 of an input file (OpenSSL), recorded in every fit so a result names the exact
// bytes it came from.
#pragma once

#include "lmcal/export.hpp"

#include <filesystem>
#include <string>

namespace LMCAL_API lmcal {

// Lower-case hex digest; InputError if the file cannot be read.
std::string sha256_file(const std::filesystem::path& file);

}  // namespace lmcal
