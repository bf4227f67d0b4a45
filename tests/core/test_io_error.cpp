// File-system failures: the machine's limits are user errors (exit 2) that say what to do.
#include <gtest/gtest.h>

#include <cerrno>

#include "core/error.h"
#include "core/io_error.h"

using namespace cgsr;

TEST(IoError, TheMachinesLimitsAreUserErrorsNamingTheFix) {
  const struct {
    int error_number;
    const char* message;
  } cases[] = {
      {ENOSPC, "cannot write: no space left on the device; free some space there or choose another --out"},
      {EDQUOT, "cannot write: no space left on the device; free some space there or choose another --out"},
      {EROFS, "cannot write: the file system is read-only; choose another --out"},
      {EACCES, "cannot write: permission denied; choose a folder you may write to (--out)"},
      {EFBIG, "cannot write: the file is larger than the file system or the process's file size limit allows"},
  };
  for (const auto& c : cases) {
    const Error e = file_system_error("/runs/x/model.cgsr", c.error_number, "write");
    EXPECT_EQ(e.kind(), ErrorKind::User) << c.error_number;
    EXPECT_EQ(e.context(), "/runs/x/model.cgsr");
    EXPECT_EQ(e.message(), c.message);
  }
}

TEST(IoError, OtherFailuresAreInternal) {
  const Error e = file_system_error("/runs/x", EIO, "write");
  EXPECT_EQ(e.kind(), ErrorKind::Internal);
  EXPECT_NE(e.message().find("cannot write: "), std::string::npos);
}
