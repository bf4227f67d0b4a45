#pragma once
// Crash-safe file writes: content goes to a temporary file next to the target, is flushed to
// disk, then renamed over the target. A killed process leaves either the old file or the new
// one, never a half-written one (a stray "*.tmp-<pid>" file at worst).

#include <filesystem>
#include <functional>
#include <string>

namespace cgsr {

// A full disk, a read-only folder or missing permissions are user errors naming the file and the
// fix (core/io_error.h); the temporary file is removed and the old file stays.
//
// Test seam: with CGSR_FAULT_NO_SPACE=<file name>[@<n>] in the environment, every write of a file
// of that name after the first n fails as on a full disk (the tests of checkpoints and model
// files on a full disk; mounting a small file system needs root).
void write_file_atomic(const std::filesystem::path& path, const std::string& content);

// For writers that can only write to a path: `write` fills the temporary path. A writer that
// can write to memory should, and pass the bytes to write_file_atomic: LibTorch's archive writer
// throws from its destructor when the disk is full, which ends the process.
void write_atomic_with(const std::filesystem::path& path,
                       const std::function<void(const std::filesystem::path& temporary)>& write);

std::string read_file(const std::filesystem::path& path);

}  // namespace cgsr
