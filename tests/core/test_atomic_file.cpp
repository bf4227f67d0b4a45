#include <gtest/gtest.h>

#include <filesystem>

#include "core/atomic_file.h"
#include "core/error.h"
#include "tests/support/scratch_dir.h"

using namespace cgsr;
namespace fs = std::filesystem;

namespace {
size_t file_count(const fs::path& dir) {
  return static_cast<size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}
}  // namespace

TEST(AtomicFile, WritesAndReplaces) {
  const auto dir = test::scratch_dir("atomic");
  write_file_atomic(dir / "a.txt", "first");
  write_file_atomic(dir / "a.txt", "second");
  EXPECT_EQ(read_file(dir / "a.txt"), "second");
  EXPECT_EQ(file_count(dir), 1u);  // no temporary left behind
}

TEST(AtomicFile, AFailingWriterKeepsTheOldFile) {
  const auto dir = test::scratch_dir("atomic-fail");
  write_file_atomic(dir / "a.txt", "old");
  EXPECT_THROW(write_atomic_with(dir / "a.txt",
                                 [](const fs::path& tmp) {
                                   write_file_atomic(tmp, "half");
                                   throw Error("writer", "interrupted");
                                 }),
               Error);
  EXPECT_EQ(read_file(dir / "a.txt"), "old");
  EXPECT_EQ(file_count(dir), 1u);
}

TEST(AtomicFile, MissingFileNamesIt) {
  try {
    read_file("/nonexistent/cgsr/file.txt");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/cgsr/file.txt"), std::string::npos);
  }
}

// Renaming over a directory fails; the message once read "Success" (the clean-up's error code).
TEST(AtomicFile, ADirectoryInTheWayIsNamedNotSuccess) {
  const auto dir = test::scratch_dir("atomic-dir");
  fs::create_directories(dir / "model.onnx" / "inside");
  try {
    write_file_atomic(dir / "model.onnx", "bytes");
    FAIL();
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find("Success"), std::string::npos) << what;
    EXPECT_NE(what.find("model.onnx: cannot move the finished file into place: a directory of that name is in the way"),
              std::string::npos)
        << what;
  }
  EXPECT_EQ(file_count(dir), 1u);  // the temporary is gone
}

// A full disk is a user error naming the file and the fix; the old file stays, no temporary is
// left, and other files are still written (CGSR_FAULT_NO_SPACE counts per file name).
TEST(AtomicFile, AFullDiskKeepsTheOldFileAndSaysWhatToDo) {
  const auto dir = test::scratch_dir("atomic-no-space");
  ::setenv("CGSR_FAULT_NO_SPACE", "model.cgsr@1", 1);
  write_file_atomic(dir / "model.cgsr", "good");
  try {
    write_file_atomic(dir / "model.cgsr", "newer");
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::User);
    EXPECT_EQ(e.context(), (dir / "model.cgsr").string());
    EXPECT_EQ(e.message(), "cannot write: no space left on the device; free some space there or choose another --out");
  }
  write_file_atomic(dir / "other.txt", "fine");
  ::unsetenv("CGSR_FAULT_NO_SPACE");
  EXPECT_EQ(read_file(dir / "model.cgsr"), "good");
  EXPECT_EQ(file_count(dir), 2u);
}
