#pragma once
// Logging through spdlog: a console sink (stderr) for the user, plus a log file per run.

#include <filesystem>
#include <string>

namespace cgsr {

// Sets up the default logger; level is trace|debug|info|warn|error|off.
void init_logging(const std::string& level);

// Also writes the log to `<path>.partial`, renamed to `path` by finish_log_file(): a killed
// command leaves its log as log.txt.partial, never a log.txt that looks complete.
void attach_log_file(const std::filesystem::path& path);
void finish_log_file();

}  // namespace cgsr
