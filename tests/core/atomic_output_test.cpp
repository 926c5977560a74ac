#include "tvf/core/atomic_output.h"

#include "tvf/core/error.h"
#include "support/test_paths.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <csignal>
#include <set>
#include <stdexcept>

#include <sys/wait.h>
#include <unistd.h>

namespace tvf {
namespace {

namespace fs = std::filesystem;
using test::read_text;
using test::TempDir;
using test::write_text;

// Names of the entries of a folder, sorted.
std::vector<std::string> listing(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

TEST(TemporarySibling, SameFolderHiddenAndUnique) {
  const fs::path target = fs::path("some") / "dir" / "field.npy";
  std::set<fs::path> seen;
  for (int k = 0; k < 100; ++k) {
    const fs::path tmp = temporary_sibling(target);
    EXPECT_EQ(tmp.parent_path(), target.parent_path());
    const std::string name = tmp.filename().string();
    EXPECT_EQ(name.rfind(".field.npy.tmp-", 0), 0u) << name;
    EXPECT_TRUE(seen.insert(tmp).second) << "repeated name " << tmp;
  }
}

TEST(WriteFileAtomically, WritesAndReplacesLeavingNoTemporaries) {
  TempDir dir;
  const fs::path file = dir / "a.txt";
  const std::string binary("x\0y\n\xff", 5);
  write_file_atomically(file, binary);
  EXPECT_EQ(read_text(file), binary);
  write_file_atomically(file, "second");
  EXPECT_EQ(read_text(file), "second");
  EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"a.txt"});
}

TEST(WriteFileAtomically, MissingFolderIsAnErrorNamingThePath) {
  TempDir dir;
  const fs::path file = dir / "missing" / "a.txt";
  try {
    write_file_atomically(file, "x");
    FAIL() << "expected tvf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
  }
  EXPECT_TRUE(listing(dir.path()).empty());
}

TEST(OutputStage, CommitMovesFilesIntoANewTargetFolder) {
  TempDir dir;
  const fs::path target = dir / "out" / "nested";
  std::vector<fs::path> written;
  {
    OutputStage stage(target);
    EXPECT_TRUE(fs::is_directory(stage.stage()));
    EXPECT_EQ(stage.stage().parent_path(), target);
    EXPECT_EQ(stage.file("b.txt"), stage.stage() / "b.txt");
    write_text(stage.file("b.txt"), "B");
    write_file_atomically(stage.file("a.txt"), "A");
    written = stage.commit();
  }
  EXPECT_EQ(written, (std::vector<fs::path>{target / "a.txt", target / "b.txt"}));
  EXPECT_EQ(listing(target), (std::vector<std::string>{"a.txt", "b.txt"}));
  EXPECT_EQ(read_text(target / "a.txt"), "A");
  EXPECT_EQ(read_text(target / "b.txt"), "B");
}

TEST(OutputStage, CommitReplacesFilesAndKeepsOthers) {
  TempDir dir;
  write_text(dir / "keep.txt", "keep");
  write_text(dir / "a.txt", "old");
  {
    OutputStage stage(dir.path());
    write_text(stage.file("a.txt"), "new");
    // Staged files are invisible in the target until commit.
    EXPECT_EQ(read_text(dir / "a.txt"), "old");
    stage.commit();
  }
  EXPECT_EQ(listing(dir.path()), (std::vector<std::string>{"a.txt", "keep.txt"}));
  EXPECT_EQ(read_text(dir / "a.txt"), "new");
}

TEST(OutputStage, UncommittedStageRemovesItsFilesAndTheFolderItCreated) {
  TempDir dir;
  const fs::path target = dir / "out";
  {
    OutputStage stage(target);
    write_text(stage.file("a.txt"), "A");
  }
  EXPECT_FALSE(fs::exists(target));
  EXPECT_TRUE(listing(dir.path()).empty());
}

TEST(OutputStage, UncommittedStageKeepsAnExistingTargetAsItWas) {
  TempDir dir;
  write_text(dir / "a.txt", "old");
  {
    OutputStage stage(dir.path());
    write_text(stage.file("a.txt"), "new");
    write_text(stage.file("b.txt"), "B");
  }
  EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"a.txt"});
  EXPECT_EQ(read_text(dir / "a.txt"), "old");
}

TEST(OutputStage, ThrowingWriterLeavesNothingBehind) {
  TempDir dir;
  const fs::path target = dir / "out";
  auto run = [&] {
    OutputStage stage(target);
    write_file_atomically(stage.file("field.npy"), "data");
    write_text(stage.file("partial.vtu"), "half a fi");
    throw std::runtime_error("writer failed");
  };
  EXPECT_THROW(run(), std::runtime_error);
  EXPECT_FALSE(fs::exists(target));
  EXPECT_TRUE(listing(dir.path()).empty());
}

TEST(OutputStage, TargetThatIsAFileIsAnErrorNamingIt) {
  TempDir dir;
  const fs::path target = dir / "file";
  write_text(target, "x");
  try {
    OutputStage stage(target);
    FAIL() << "expected tvf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(target.string()), std::string::npos) << e.what();
  }
  EXPECT_EQ(read_text(target), "x");
}

// --- Issue 17 item 7: folders committed as a whole, stale staging cleaned.

TEST(OutputStage, CommitRemovesTheOwnedFilesOfAnEarlierRunAndKeepsOthers) {
  TempDir dir;
  write_text(dir / "field_0000.vtu", "old");
  write_text(dir / "field_0099.vtu", "old");
  write_text(dir / "field.pvd", "old");
  write_text(dir / "notes.txt", "mine");
  {
    OutputStage stage(dir.path());
    write_text(stage.file("field_0000.vtu"), "new");
    stage.commit([](const std::string& name) { return name.rfind("field", 0) == 0; });
  }
  EXPECT_EQ(listing(dir.path()), (std::vector<std::string>{"field_0000.vtu", "notes.txt"}));
  EXPECT_EQ(read_text(dir / "field_0000.vtu"), "new");
}

TEST(OutputStage, StagingFoldersOfDeadProcessesAreRemovedOnStart) {
  TempDir dir;
  // A process that has ended: its pid names no process any more.
  const pid_t child = fork();
  if (child == 0) _exit(0);
  ASSERT_GT(child, 0);
  int status = 0;
  waitpid(child, &status, 0);
  const fs::path dead = dir / (".tvf-stage-" + std::to_string(child) + "-0");
  fs::create_directory(dead);
  write_text(dead / "field.npy", "half");
  // One of a live process (this one's parent) stays: a run may be writing there now.
  const fs::path live = dir / (".tvf-stage-" + std::to_string(getppid()) + "-0");
  fs::create_directory(live);
  {
    OutputStage stage(dir.path());
    stage.commit();
  }
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_TRUE(fs::exists(live));
}

TEST(OutputStage, SigtermRemovesTheStagingFolder) {
  TempDir dir;
  const pid_t child = fork();
  if (child == 0) {
    install_output_cleanup_on_signals();
    OutputStage stage(dir.path());
    write_text(stage.file("field.npy"), "half");
    write_text(dir / "ready", "");
    for (;;) pause();
  }
  ASSERT_GT(child, 0);
  for (int k = 0; k < 500 && !fs::exists(dir / "ready"); ++k) usleep(10'000);
  ASSERT_TRUE(fs::exists(dir / "ready"));
  kill(child, SIGTERM);
  int status = 0;
  waitpid(child, &status, 0);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGTERM) << status;
  EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"ready"});
}

TEST(OutputStage, AnInterruptedCommitIsRefusedByReaders) {
  TempDir dir;
  EXPECT_NO_THROW(check_output_complete(dir.path()));
  write_text(dir / kCommitMarker, "");
  EXPECT_NE(test::error_of([&] { check_output_complete(dir.path()); }).find("interrupted output"), std::string::npos);
  // The next commit into the folder makes it whole again.
  {
    OutputStage stage(dir.path());
    write_text(stage.file("a.txt"), "A");
    stage.commit();
  }
  EXPECT_NO_THROW(check_output_complete(dir.path()));
  EXPECT_EQ(listing(dir.path()), std::vector<std::string>{"a.txt"});
}

TEST(OutputStage, AnEmptyTargetIsRefused) {
  EXPECT_EQ(test::error_of([] { OutputStage stage(""); }),
            "the output folder is an empty path; give a folder (\".\" for the current one)");
}

}  // namespace
}  // namespace tvf
