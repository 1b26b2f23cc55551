// Text from files and paths made safe to print on a terminal or in a message.
#pragma once

#include "lmcal/export.hpp"

#include <string>
#include <string_view>

namespace LMCAL_API lmcal {
namespace io {

// `text` safe to print: bytes that are not UTF-8 as \xE9, control and bidirectional
// characters as \u001B; everything else as it is.
std::string printable(std::string_view text);

}  // namespace io
}  // namespace lmcal
