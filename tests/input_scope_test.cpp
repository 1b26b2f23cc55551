// Files an input names stay inside its root: a manifest's `file` or `catalog` outside its folder
// (by `..`, an absolute path or a link) is refused at its line before anything is opened, with
// the same words whether the file exists or not; --allow-outside-root (allow_outside) lifts it;
// a fleet's root lets its sets share a file. And an output folder lmcal could not write into is
// told before any work.
#include "lmcal/io/input_scope.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "lmcal/error.hpp"
#include "lmcal/io/atomic_file.hpp"
#include "lmcal/io/friction_log.hpp"
#include "lmcal/predict/prediction.hpp"
#include "support/temp_folder.hpp"

namespace lmcal {
namespace {

namespace fs = std::filesystem;

class InputScopeTest : public test::TempFolderTest {
 protected:
  // load_friction_dataset's refusal of a manifest that names `file`, or "" when accepted.
  std::string refusal(const std::string& file, const InputScope& scope = {}) const {
    const fs::path manifest = write("set/friction.toml", "# a friction manifest\nfile = \"" + file + "\"\n");
    try {
      load_friction_dataset(manifest, nullptr, {}, {}, scope);
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }
};

TEST_F(InputScopeTest, APathOutsideTheFolderIsRefusedAtItsLineBeforeItIsOpened) {
  write("secret.csv", "time_s,tc1_C\n0,20\n");
  const std::string exists = refusal("../secret.csv");
  EXPECT_NE(exists.find("friction.toml:2:8: file '../secret.csv' is outside"), std::string::npos) << exists;
  EXPECT_NE(exists.find("--allow-outside-root"), std::string::npos) << exists;
  // No oracle: a missing file outside is refused in the same words.
  const std::string missing = refusal("../missing.csv");
  EXPECT_EQ(missing.substr(missing.find("is outside")), exists.substr(exists.find("is outside")));
  const std::string absolute = refusal("/etc/passwd");
  EXPECT_NE(absolute.find("file '/etc/passwd' is outside"), std::string::npos) << absolute;
  EXPECT_EQ(absolute.find("root:"), std::string::npos) << "nothing of the file is echoed";

  fs::create_symlink(dir_ / "secret.csv", dir_ / "set" / "link.csv");
  const std::string linked = refusal("link.csv");
  EXPECT_NE(linked.find("is outside"), std::string::npos) << linked;
  EXPECT_NE(linked.find("through a symbolic link"), std::string::npos) << linked;
}

TEST_F(InputScopeTest, InsideTheFolderOrAllowedTheFileIsRead) {
  write("set/runs/r1.csv", "not a trace\n");
  write("shared/r1.csv", "not a trace\n");
  // Past the scope, the loader reads the file and refuses its content: proof it got that far.
  const std::string inside = refusal("runs/r1.csv");
  EXPECT_EQ(inside.find("is outside"), std::string::npos) << inside;
  EXPECT_NE(inside.find("r1.csv"), std::string::npos) << inside;
  for (const InputScope& scope : {InputScope{.allow_outside = true}, InputScope{.root = dir_}}) {
    const std::string shared = refusal("../shared/r1.csv", scope);
    EXPECT_EQ(shared.find("is outside"), std::string::npos) << shared;
    EXPECT_NE(shared.find("shared/r1.csv"), std::string::npos) << shared;
  }
  EXPECT_NE(refusal("../shared/r1.csv", InputScope{.root = dir_ / "set"}).find("is outside"), std::string::npos);
}

TEST_F(InputScopeTest, ADutysCatalogStaysInsideItsFolder) {
  write("catalog.toml", "[[guide]]\nmodel = \"X\"\n");
  const fs::path duty = write("duty/duty.toml", "guide = \"SRN 35C\"\ncatalog = \"../catalog.toml\"\n");
  try {
    load_duty_cycle(duty);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("duty.toml:2:11: file '../catalog.toml' is outside"), std::string::npos) << e.what();
  }
}

TEST_F(InputScopeTest, AnOutputFolderThatCannotBeWrittenIsToldBeforeAnyWork) {
  EXPECT_EQ(output_folder_problem(dir_ / "new" / "deeper"), std::nullopt) << "a folder the commit will create";
  const fs::path file = write("file.txt", "x");
  const auto under_file = output_folder_problem(file / "out");
  ASSERT_TRUE(under_file.has_value());
  EXPECT_NE(under_file->find("file.txt is not a folder"), std::string::npos) << *under_file;
  const auto full = output_folder_problem(dir_, std::numeric_limits<std::uintmax_t>::max() / 2);
  ASSERT_TRUE(full.has_value()) << "no disk has 8 EiB free";
  EXPECT_NE(full->find("free in"), std::string::npos) << *full;
  if (::geteuid() != 0) {  // root writes anywhere
    fs::create_directory(dir_ / "readonly");
    fs::permissions(dir_ / "readonly", fs::perms::owner_read | fs::perms::owner_exec);
    const auto readonly = output_folder_problem(dir_ / "readonly" / "out");
    fs::permissions(dir_ / "readonly", fs::perms::owner_all);
    ASSERT_TRUE(readonly.has_value());
    EXPECT_NE(readonly->find("Permission denied"), std::string::npos) << *readonly;
  }
}

}  // namespace
}  // namespace lmcal
