// Private: TOML text for the manifest writers (the thermal manifest, the virtual rig's friction
// manifest), without the parser's header.
#pragma once

#include <string>
#include <string_view>

namespace lmcal::manifest {

// A TOML basic string: quoted, with quotes, backslashes and control characters escaped.
std::string toml_string(std::string_view s);

}  // namespace lmcal::manifest
