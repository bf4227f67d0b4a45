#include "core/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include "core/error.h"
#include "core/io_error.h"

namespace cgsr {
namespace fs = std::filesystem;

namespace {
fs::path temporary_for(const fs::path& path) {
  return path.string() + ".tmp-" + std::to_string(::getpid());
}

// The test seam of CGSR_FAULT_NO_SPACE (atomic_file.h): true when this write of `path` is one to
// fail. Counted per file name, so "checkpoint.pt@1" lets the first checkpoint through.
bool injected_no_space(const fs::path& path) {
  const char* spec = std::getenv("CGSR_FAULT_NO_SPACE");
  if (!spec || !*spec) return false;
  const std::string text = spec;
  const size_t at = text.find('@');
  const std::string name = text.substr(0, at);
  if (path.filename() != name) return false;
  const long pass = at == std::string::npos ? 0 : std::atol(text.c_str() + at + 1);
  static std::mutex mutex;
  static std::map<std::string, long> written;
  const std::lock_guard lock(mutex);
  return written[name]++ >= pass;
}

void sync_file(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

void commit(const fs::path& temporary, const fs::path& path) {
  sync_file(temporary);
  std::error_code ec;
  fs::rename(temporary, path, ec);
  if (ec) {
    // The message is taken before the clean-up, whose own error code would overwrite it.
    std::string why = ec.message();
    if (fs::is_directory(path)) why = "a directory of that name is in the way (remove it or choose another name)";
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw Error(path.string(), "cannot move the finished file into place: " + why);
  }
}

void create_parent(const fs::path& path) {
  if (!path.has_parent_path()) return;
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  if (ec) throw file_system_error(path.parent_path(), ec.value(), "create the folder");
}

// Writes `content` to `temporary` and flushes it to the disk; a full disk may only show at
// fsync or close, so both are checked.
void write_bytes(const fs::path& temporary, const fs::path& path, const std::string& content) {
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw file_system_error(path, errno, "write");
  const auto fail = [&](int error_number) {
    ::close(fd);
    return file_system_error(path, error_number, "write");
  };
  if (injected_no_space(path)) throw fail(ENOSPC);
  size_t done = 0;
  while (done < content.size()) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw fail(errno);
    done += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0 && errno != EINVAL) throw fail(errno);
  if (::close(fd) != 0) throw file_system_error(path, errno, "write");
}
}  // namespace

void write_atomic_with(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  create_parent(path);
  const fs::path temporary = temporary_for(path);
  try {
    write(temporary);
  } catch (...) {
    std::error_code ec;
    fs::remove(temporary, ec);
    throw;
  }
  if (!fs::exists(temporary)) throw Error(path.string(), "the writer produced no file", ErrorKind::Internal);
  commit(temporary, path);
}

void write_file_atomic(const fs::path& path, const std::string& content) {
  create_parent(path);
  const fs::path temporary = temporary_for(path);
  try {
    write_bytes(temporary, path, content);
  } catch (...) {
    std::error_code ec;
    fs::remove(temporary, ec);
    throw;
  }
  commit(temporary, path);
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string(), fs::exists(path) ? "cannot read the file" : "no such file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

}  // namespace cgsr
