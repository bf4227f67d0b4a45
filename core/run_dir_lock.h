#pragma once
// One writer per run directory: an advisory lock (flock) on DIR/.cgsr.lock, held for a command's
// lifetime and released by the kernel however the process ends. The file records the holder's
// PID and command; it stays when the command ends, so the directory remembers which command it
// belongs to, and another command is refused there unless forced.

#include <filesystem>
#include <string>

namespace cgsr {

class RunDirLock {
 public:
  // Creates `dir` when missing and locks it for `command` ("train", "eval", ...). A user error
  // when another process holds it (naming that process), or when `dir` belongs to another
  // command and `force` is false.
  RunDirLock(const std::filesystem::path& dir, const std::string& command, bool force);
  ~RunDirLock();
  RunDirLock(const RunDirLock&) = delete;
  RunDirLock& operator=(const RunDirLock&) = delete;

  static constexpr const char* kFileName = ".cgsr.lock";

 private:
  int fd_ = -1;
};

}  // namespace cgsr
