#include "core/io_error.h"

#include <cerrno>
#include <cstring>

namespace cgsr {

Error file_system_error(const std::filesystem::path& path, int error_number, const std::string& doing) {
  const std::string cannot = "cannot " + doing + ": ";
  switch (error_number) {
    case ENOSPC:
    case EDQUOT:
      return Error(path.string(), cannot + "no space left on the device; free some space there or choose another --out");
    case EROFS:
      return Error(path.string(), cannot + "the file system is read-only; choose another --out");
    case EACCES:
    case EPERM:
      return Error(path.string(), cannot + "permission denied; choose a folder you may write to (--out)");
    case EFBIG:
      return Error(path.string(), cannot + "the file is larger than the file system or the process's file size limit allows");
    case ENAMETOOLONG:
      return Error(path.string(), cannot + "the path or one of its names is too long");
    case ENOTDIR:
      return Error(path.string(), cannot + "a part of the path is a file, not a folder");
    default:
      return Error(path.string(), cannot + std::strerror(error_number), ErrorKind::Internal);
  }
}

}  // namespace cgsr
