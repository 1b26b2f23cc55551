// Output sets are all new or all old whatever kills the writer and wherever: a child process
// is killed at every step of a commit (SIGKILL: nothing runs after it) or interrupted there
// (SIGINT: held until the commit is over), two writers share a folder, and a failing commit
// leaves nothing of itself.
#include "lmcal/io/atomic_file.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <iterator>
#include <map>
#include <stdexcept>
#include <thread>

#include "io/atomic_file_steps.hpp"
#include "lmcal/error.hpp"
#include "support/temp_folder.hpp"

namespace lmcal {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kNames{"a.json", "b.csv", "c.html"};

std::pair<int, int> stop_at;  // step, signal: the child's hook reads it (a plain function pointer)

class OutputSetTest : public test::TempFolderTest {
 protected:
  // The folder's files, name -> contents (hidden ones too).
  std::map<std::string, std::string> folder() const {
    std::map<std::string, std::string> files;
    for (const auto& entry : fs::directory_iterator(dir_)) {
      std::ifstream in(entry.path(), std::ios::binary);
      files[entry.path().filename().string()] = std::string(std::istreambuf_iterator<char>(in), {});
    }
    return files;
  }
  // A set of every name with contents tagged `tag`; the earlier set's d.txt removed.
  OutputSet set(const std::string& tag) const {
    OutputSet out;
    for (const auto& name : kNames) out.add(dir_ / name, tag + " " + name);
    out.remove(dir_ / "d.txt");
    return out;
  }
  std::map<std::string, std::string> expected(const std::string& tag, bool with_d) const {
    std::map<std::string, std::string> files;
    for (const auto& name : kNames) files[name] = tag + " " + name;
    if (with_d) files["d.txt"] = "old d.txt";
    return files;
  }
  void write_old() const {
    for (const auto& name : kNames) write(name, "old " + name);
    write("d.txt", "old d.txt");
  }
  // Over the old set: the new one committed in a child that raises `signal` at `step`; returns
  // how the child ended.
  // `elsewhere`: the signal lands on another thread of the child (a fleet's other job).
  int commit_stopped_at(int step, int signal, bool elsewhere = false) const {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    write_old();
    stop_at = {step, signal};
    if (elsewhere)
      return commit_in_child([](int k) {
        if (k == stop_at.first) std::thread([] { ::raise(stop_at.second); }).join();
      });
    return commit_in_child([](int k) {
      if (k == stop_at.first) ::raise(stop_at.second);
    });
  }
  // Commits the new set in a child that `hook` may stop; returns how the child ended.
  int commit_in_child(void (*hook)(int)) const {
    const pid_t child = ::fork();
    if (child == 0) {
      detail::commit_step_hook = hook;
      try {
        set("new").commit();
      } catch (...) {
        ::_exit(3);
      }
      ::_exit(0);
    }
    int status = 0;
    ::waitpid(child, &status, 0);
    return status;
  }
};

TEST_F(OutputSetTest, AKillAtAnyStepLeavesTheOldSetOrTheNewOne) {
  const std::vector<int> steps{1, 2, 3, 50, 51, 100, 101, 102, 103, 104};
  for (int k : steps) {
    SCOPED_TRACE(testing::Message() << "killed at step " << k);
    const int status = commit_stopped_at(k, SIGKILL);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) << "the child was not killed there";
    recover_outputs(dir_);  // what the next run does first
    const auto files = folder();
    if (k < 51) {
      EXPECT_EQ(files, expected("old", true)) << "killed before the commit point: the old set";
    } else {
      EXPECT_EQ(files, expected("new", false)) << "killed after the commit point: the new set, finished";
    }
  }
}

TEST_F(OutputSetTest, CtrlCDuringTheCommitWaitsUntilItIsOver) {
  for (int k : {2, 51, 101}) {
    SCOPED_TRACE(testing::Message() << "SIGINT at step " << k);
    const int status = commit_stopped_at(k, SIGINT);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << "Ctrl-C is delivered once the set is in place";
    EXPECT_EQ(folder(), expected("new", false)) << "no temporary left, nothing old mixed in";
  }
}

TEST_F(OutputSetTest, CtrlCOnAnotherThreadAlsoWaitsUntilTheCommitIsOver) {
  for (int k : {2, 51, 101}) {
    SCOPED_TRACE(testing::Message() << "SIGINT on another thread at step " << k);
    const int status = commit_stopped_at(k, SIGINT, true);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGINT) << "Ctrl-C is delivered once the set is in place";
    EXPECT_EQ(folder(), expected("new", false)) << "no temporary left, nothing old mixed in";
  }
}

TEST_F(OutputSetTest, TheNextCommitFinishesWhatAKilledOneLeft) {
  ASSERT_TRUE(WIFSIGNALED(commit_stopped_at(101, SIGKILL)));
  EXPECT_TRUE(fs::exists(dir_ / ".lmcal-commit")) << "killed in the middle of the renames: the journal stays";
  OutputSet next;
  next.add(dir_ / "e.txt", "e");
  next.commit();
  auto want = expected("new", false);
  want["e.txt"] = "e";
  EXPECT_EQ(folder(), want);
}

TEST_F(OutputSetTest, TwoWritersIntoOneFolderNeverMixTheirFiles) {
  for (int round = 0; round < 20; ++round) {
    std::thread a([&] { set("A").commit(); });
    std::thread b([&] { set("B").commit(); });
    a.join();
    b.join();
    const auto files = folder();
    EXPECT_TRUE(files == expected("A", false) || files == expected("B", false)) << "round " << round;
  }
}

TEST_F(OutputSetTest, AFailedCommitLeavesNothingOfItself) {
  OutputSet out;
  out.add(dir_ / "new" / "deeper" / "ok.txt", "fine");
  out.add(dir_ / "new" / "deeper" / std::string(300, 'x'), "a name too long for the file system");
  try {
    out.commit();
    FAIL() << "committed a file whose name is too long";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("File name too long"), std::string::npos) << "the system's reason: " << e.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "new")) << "the folders it created are removed again";
  EXPECT_TRUE(folder().empty());
}

TEST_F(OutputSetTest, TheSamePathTwiceIsRefused) {
  OutputSet out;
  out.add(dir_ / "run.csv", "one");
  EXPECT_THROW(out.add(dir_ / "run.csv", "two"), std::invalid_argument);
}

}  // namespace
}  // namespace lmcal
