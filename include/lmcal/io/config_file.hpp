// The options file of `lmcal --config FILE` (TOML: a [command] table of option = value),
// checked before the command line's parser reads it.
#pragma once

#include "lmcal/export.hpp"

#include <filesystem>

namespace LMCAL_API lmcal {
namespace io {

// Refuses, with an InputError, a config file that is not a regular file of at most 64 MiB
// (like every input: /dev/zero is refused before a byte is read) or that opens a [table] twice
// ("options.toml:4:1: [calibrate] given twice (first at line 1): …"), which CLI11 would merge
// without a word. Arrays of tables ([[x]]) may repeat.
void check_config_file(const std::filesystem::path& file);

}  // namespace io
}  // namespace lmcal
