#include "support/source_paths.hpp"

namespace lmcal::test {

std::filesystem::path source_dir() { return LMCAL_SOURCE_DIR; }
std::filesystem::path test_data_dir() { return LMCAL_TEST_DATA_DIR; }

}  // namespace lmcal::test
