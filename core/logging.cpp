#include "core/logging.h"

#include <fcntl.h>
#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/sinks/dist_sink.h>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cerrno>

#include "core/error.h"
#include "core/io_error.h"

namespace cgsr {
namespace {
struct LogState {
  std::shared_ptr<spdlog::sinks::dist_sink_mt> sinks;
  std::shared_ptr<spdlog::sinks::basic_file_sink_mt> file;
  std::filesystem::path file_path;
};
LogState& state() {
  static LogState s;
  return s;
}
}  // namespace

void init_logging(const std::string& level) {
  auto& s = state();
  if (!s.sinks) {
    s.sinks = std::make_shared<spdlog::sinks::dist_sink_mt>();
    auto console = std::make_shared<spdlog::sinks::stderr_color_sink_mt>(
        ::isatty(STDERR_FILENO) ? spdlog::color_mode::automatic : spdlog::color_mode::never);
    console->set_pattern("[%H:%M:%S] %^%l%$ %v");
    s.sinks->add_sink(console);
    auto logger = std::make_shared<spdlog::logger>("cgsr", s.sinks);
    // Every message reaches the log file at once (the file sink buffers otherwise): a killed run's
    // log.txt.partial then holds everything up to the kill, not an empty or cut-off buffer.
    logger->flush_on(spdlog::level::trace);
    spdlog::set_default_logger(logger);
  }
  const auto parsed = spdlog::level::from_str(level);
  if (parsed == spdlog::level::off && level != "off")
    throw Error("--log-level", "unknown level '" + level + "'; valid: trace, debug, info, warn, error, off");
  spdlog::set_level(parsed);
}

void attach_log_file(const std::filesystem::path& path) {
  auto& s = state();
  if (!s.sinks) init_logging("info");
  finish_log_file();
  std::error_code ec;
  std::filesystem::create_directories(path.parent_path(), ec);
  if (ec) throw file_system_error(path.parent_path(), ec.value(), "create the folder");
  // Opened here first for errno: spdlog's own failure says only "Failed opening file".
  const std::string partial = path.string() + ".partial";
  const int fd = ::open(partial.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) throw file_system_error(partial, errno, "write the log");
  ::close(fd);
  s.file_path = path;
  s.file = std::make_shared<spdlog::sinks::basic_file_sink_mt>(partial, /*truncate=*/true);
  s.file->set_pattern("[%Y-%m-%d %H:%M:%S.%e] [%l] %v");
  s.sinks->add_sink(s.file);
}

void finish_log_file() {
  auto& s = state();
  if (!s.file) return;
  s.file->flush();
  s.sinks->remove_sink(s.file);
  s.file.reset();
  std::error_code ec;
  std::filesystem::rename(s.file_path.string() + ".partial", s.file_path, ec);
}

}  // namespace cgsr
