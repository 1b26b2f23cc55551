// Where the test data and the source tree are. Their absolute paths are compiled into one file
// (source_paths.cpp) only, so that the other test files compile to the same objects in any clone
// and a compiler cache serves them all (CMakeLists.txt: LMCAL_CCACHE).
#pragma once

#include <filesystem>

namespace lmcal::test {

std::filesystem::path source_dir();     // the project's root (CMakeLists.txt, fits/, examples/)
std::filesystem::path test_data_dir();  // tests/data

}  // namespace lmcal::test
