#include "lmcal/version.hpp"

#include <boost/version.hpp>
#include <ceres/version.h>
#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <nlopt.hpp>
#include <openssl/opensslv.h>
#include <toml++/toml.h>

#include <Eigen/Core>

#include "lmcal_git_commit.hpp"

namespace lmcal {

std::vector<std::pair<std::string, std::string>> software_versions() {
  int major = 0, minor = 0, bugfix = 0;
  nlopt::version(major, minor, bugfix);
  return {{"lmcal", LMCAL_VERSION},
          {"Ceres Solver", CERES_VERSION_STRING},
          {"Eigen", fmt::format("{}.{}.{}", EIGEN_WORLD_VERSION, EIGEN_MAJOR_VERSION, EIGEN_MINOR_VERSION)},
          {"NLopt", fmt::format("{}.{}.{}", major, minor, bugfix)},
          {"fmt", fmt::format("{}.{}.{}", FMT_VERSION / 10000, FMT_VERSION / 100 % 100, FMT_VERSION % 100)},
          {"nlohmann-json", fmt::format("{}.{}.{}", NLOHMANN_JSON_VERSION_MAJOR, NLOHMANN_JSON_VERSION_MINOR,
                                        NLOHMANN_JSON_VERSION_PATCH)},
          {"toml++", fmt::format("{}.{}.{}", TOML_LIB_MAJOR, TOML_LIB_MINOR, TOML_LIB_PATCH)},
          {"Boost", fmt::format("{}.{}.{}", BOOST_VERSION / 100000, BOOST_VERSION / 100 % 1000, BOOST_VERSION % 100)},
          {"OpenSSL", fmt::format("{}.{}.{}", OPENSSL_VERSION_MAJOR, OPENSSL_VERSION_MINOR, OPENSSL_VERSION_PATCH)},
          {"compiler", __VERSION__}};
}

std::string git_commit() { return LMCAL_GIT_COMMIT; }

}  // namespace lmcal
