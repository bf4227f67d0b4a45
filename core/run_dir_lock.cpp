#include "core/run_dir_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <spdlog/spdlog.h>

#include <cerrno>
#include <sstream>

#include "core/error.h"
#include "core/io_error.h"

namespace cgsr {
namespace fs = std::filesystem;

namespace {
struct Holder {
  long pid = 0;
  std::string command;
};

// "<pid> <command>" as the last holder wrote it; empty for a new file. The command is the rest
// of the line: "data merge" is two words.
Holder read_holder(int fd) {
  std::string text(256, '\0');
  const ssize_t n = ::pread(fd, text.data(), text.size(), 0);
  text.resize(n > 0 ? static_cast<size_t>(n) : 0);
  Holder h;
  std::istringstream in(text);
  if (in >> h.pid) std::getline(in >> std::ws, h.command);
  return h;
}
}  // namespace

RunDirLock::RunDirLock(const fs::path& dir, const std::string& command, bool force) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw file_system_error(dir, ec.value(), "create the run directory");
  const fs::path file = dir / kFileName;
  fd_ = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) throw file_system_error(file, errno, "write");
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error_number = errno;
    const Holder holder = read_holder(fd_);
    ::close(fd_);
    fd_ = -1;
    if (error_number != EWOULDBLOCK) throw file_system_error(file, error_number, "lock");
    throw Error(dir.string(), "is in use by another command ('cgsr " + holder.command + "', pid " +
                                  std::to_string(holder.pid) + "); wait for it to end or choose another --out");
  }
  const Holder previous = read_holder(fd_);
  if (!previous.command.empty() && previous.command != command) {
    if (!force) {
      ::close(fd_);
      fd_ = -1;
      throw Error(dir.string(), "belongs to 'cgsr " + previous.command + "' (" + kFileName +
                                    "); choose another --out, or pass --force to write 'cgsr " + command +
                                    "' files into it");
    }
    spdlog::warn("{}: belongs to 'cgsr {}'; writing 'cgsr {}' files into it (--force)", dir.string(),
                 previous.command, command);
  }
  const std::string record = std::to_string(::getpid()) + " " + command + "\n";
  if (::ftruncate(fd_, 0) != 0 || ::pwrite(fd_, record.data(), record.size(), 0) != static_cast<ssize_t>(record.size())) {
    const int error_number = errno;
    ::close(fd_);
    fd_ = -1;
    throw file_system_error(file, error_number, "write");
  }
}

RunDirLock::~RunDirLock() {
  if (fd_ >= 0) ::close(fd_);  // releases the lock
}

}  // namespace cgsr
