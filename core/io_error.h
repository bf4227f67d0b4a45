#pragma once
// What a failed file-system call means for the user. The machine's limits (a full disk, a
// read-only or foreign folder, a file size limit) are user errors, exit code 2, with the fix;
// any other failure is internal.

#include <filesystem>
#include <string>

#include "core/error.h"

namespace cgsr {

// The error for `path` after `doing` (e.g. "write", "create the folder") failed with errno
// `error_number`.
Error file_system_error(const std::filesystem::path& path, int error_number, const std::string& doing);

}  // namespace cgsr
