#pragma once
// Crash-safe file writes: content goes to a temporary file next to the target, is flushed to
// disk, then renamed over the target. A killed process leaves either the old file or the new
// one, never a half-written one (a stray "*.tmp-<pid>" file at worst).

#include <filesystem>
#include <functional>
#include <string>

namespace cgsr {

void write_file_atomic(const std::filesystem::path& path, const std::string& content);

// For writers that need a path (image encoders, torch::save): `write` fills the temporary path.
void write_atomic_with(const std::filesystem::path& path,
                       const std::function<void(const std::filesystem::path& temporary)>& write);

std::string read_file(const std::filesystem::path& path);

}  // namespace cgsr
