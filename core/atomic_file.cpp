#include "core/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "core/error.h"

namespace cgsr {
namespace fs = std::filesystem;

namespace {
fs::path temporary_for(const fs::path& path) {
  return path.string() + ".tmp-" + std::to_string(::getpid());
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
}  // namespace

void write_atomic_with(const fs::path& path, const std::function<void(const fs::path&)>& write) {
  if (path.has_parent_path()) fs::create_directories(path.parent_path());
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
  write_atomic_with(path, [&](const fs::path& temporary) {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(path.string(), std::string("cannot open for writing: ") + std::strerror(errno));
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    if (!out) throw Error(path.string(), "write failed (disk full?)");
  });
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string(), fs::exists(path) ? "cannot read the file" : "no such file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

}  // namespace cgsr
