// The bad-input corpus (tests/data/bad/; loaders: friction and thermal CSVs, friction and thermal manifests,
// friction fit JSONs as --friction reads them, duty files): every file there must be refused with exactly the
// message tests/data/bad/expected.txt gives for it, and every file must be listed there.
#include "lmcal/error.hpp"
#include "lmcal/fit/thermal_fit.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/io/thermal_run.hpp"
#include "lmcal/predict/prediction.hpp"
#include "support/source_paths.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

namespace lmcal {
namespace {

namespace fs = std::filesystem;

const fs::path kBadDir = test::test_data_dir() / "bad";
constexpr const char* kExpected = "expected.txt";

struct Case {
  std::string loader;  // friction, thermal, manifest
  std::string file;
  std::string message;
  int line;  // in expected.txt
};

// Parses expected.txt: "<loader> <file> | <message>", '#' comments and blank lines skipped.
std::vector<Case> read_cases() {
  std::ifstream in(kBadDir / kExpected);
  EXPECT_TRUE(in) << "cannot open " << (kBadDir / kExpected);
  std::vector<Case> cases;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    if (text.empty() || text[0] == '#') continue;
    const auto bar = text.find(" | ");
    const auto space = text.find(' ');
    if (bar == std::string::npos || space >= bar) {
      ADD_FAILURE() << "expected.txt:" << line << ": not '<loader> <file> | <message>': " << text;
      continue;
    }
    cases.push_back({text.substr(0, space), text.substr(space + 1, bar - space - 1), text.substr(bar + 3), line});
  }
  return cases;
}

// Runs with the corpus folder as the working directory, so messages name files relatively.
class InFolder {
 public:
  explicit InFolder(const fs::path& folder) : previous_(fs::current_path()) { fs::current_path(folder); }
  ~InFolder() { fs::current_path(previous_); }
  InFolder(const InFolder&) = delete;
  InFolder& operator=(const InFolder&) = delete;

 private:
  fs::path previous_;
};

// The message of the InputError that loading `file` throws, or a description of what happened instead.
std::string load_message(const std::string& loader, const std::string& file) {
  try {
    if (loader == "friction") {
      load_friction_log(file);
    } else if (loader == "thermal") {
      load_thermal_trace(file);
    } else if (loader == "manifest") {
      // The corpus's manifests use the runs of tests/data/good/: their root is tests/data.
      load_thermal_dataset(file, nullptr, InputScope{.root = ".."});
    } else if (loader == "frictionmanifest") {
      load_friction_dataset(file, nullptr, {}, {}, InputScope{.root = ".."});
    } else if (loader == "duty") {
      load_duty_cycle(file);
    } else if (loader == "fitjson") {
      ThermalFitOptions options;
      read_friction_fit(file, options);
    } else {
      return "unknown loader '" + loader + "'";
    }
  } catch (const InputError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("not an InputError: ") + e.what();
  }
  return "(accepted)";
}

TEST(BadInput, EveryFileIsRefusedWithTheExpectedMessage) {
  const std::vector<Case> cases = read_cases();
  ASSERT_GE(cases.size(), 20u);
  const InFolder in_corpus(kBadDir);
  for (const Case& c : cases) {
    EXPECT_EQ(load_message(c.loader, c.file), c.message) << "expected.txt:" << c.line << " (" << c.file << ")";
  }
}

TEST(BadInput, EveryFileIsListedOnce) {
  std::multiset<std::string> listed;
  for (const Case& c : read_cases()) listed.insert(c.file);
  for (const auto& entry : fs::directory_iterator(kBadDir)) {
    const std::string name = entry.path().filename().string();
    if (!entry.is_regular_file() || name == kExpected) continue;
    EXPECT_EQ(listed.count(name), 1u) << name << " must be listed once in expected.txt";
  }
  for (const std::string& name : listed) EXPECT_TRUE(fs::exists(kBadDir / name)) << name << " is listed but missing";
}

TEST(BadInput, ErrorCarriesFileLineAndCharacterColumn) {
  // The column counts characters: "Δt ≈ 5 s" is 8 characters but 12 bytes.
  const InFolder in_corpus(kBadDir);
  try {
    load_thermal_trace("thermal_utf8_column.csv");
    FAIL() << "accepted a non-numeric temperature";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "thermal_utf8_column.csv");
    EXPECT_EQ(e.line(), 3);
    EXPECT_EQ(e.column(), 17);
  }
}

TEST(BadInput, MissingFileIsAnInputError) {
  EXPECT_THROW(load_friction_log(kBadDir / "no_such_file.csv"), InputError);
  EXPECT_THROW(load_thermal_trace(kBadDir / "no_such_file.csv"), InputError);
  EXPECT_THROW(load_thermal_dataset(kBadDir / "no_such_file.toml"), InputError);
  EXPECT_THROW(load_thermal_trace(kBadDir), InputError);  // a folder
}

}  // namespace
}  // namespace lmcal
