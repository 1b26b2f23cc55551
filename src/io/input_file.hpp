// Private: every input file is opened through here, so that a folder, a device (/dev/zero),
// a pipe or an oversized file is refused before a byte is read; and the check of every name
// that reaches an output (UTF-8, no control or bidirectional characters).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

#include "lmcal/io/printable.hpp"

namespace lmcal::io {

// Why `file` cannot be read as a regular file (symlinks followed), or nullopt, with its size
// into *size: "No such file or directory", "this is a folder, not a file",
// "this is a device; expected a regular file".
std::optional<std::string> not_a_file(const std::filesystem::path& file, std::uintmax_t* size = nullptr);

// The size of `file` after checking that it is a regular file of at most `max_bytes` and that
// its name is fit for outputs (check_path_name). InputError otherwise, naming the file as `what`
// ("cannot open manifest file: this is a folder, not a file").
std::uintmax_t check_input_file(const std::filesystem::path& file, std::uintmax_t max_bytes, std::string_view what);

// The whole of a regular text file of at most kMaxTextBytes (limits.hpp), checked as above.
std::string read_text_file(const std::filesystem::path& file, std::string_view what);

// "4 GiB", "64 MiB", "1.5 KiB" (or "12 bytes"): a byte count for messages.
std::string byte_size(std::uintmax_t bytes);

// What makes `name` (a run, guide, sensor or folder name) unfit to carry into outputs, or
// nullopt: bytes that are not UTF-8 (JSON cannot hold them), control characters (a terminal
// would act on escape sequences) and bidirectional controls (U+202E reverses the text after
// it on a page). For example "byte 0xE9 at character 3 is not UTF-8 (...)".
// `free_text` allows line breaks and tabs (a description).
std::optional<std::string> name_problem(std::string_view name, bool free_text = false);

// The bidirectional control that starts `text` (its code point and length in bytes), or nullopt:
// for escapers that show it by name (the report's escape_xml).
struct BidiControl {
  char32_t code;
  std::size_t length;
};
std::optional<BidiControl> bidi_control_at(std::string_view text);

// printable(text): lmcal/io/printable.hpp.

// Throws InputError naming `path` (printably) when name_problem finds something in it:
// every path lmcal reads may end up in a JSON record. `what`: "file name", "folder name".
void check_path_name(const std::filesystem::path& path, std::string_view what);

}  // namespace lmcal::io
