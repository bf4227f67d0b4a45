#include "core/run_dir.h"

#include <ctime>

#include "core/atomic_file.h"
#include "core/config.h"
#include "core/error.h"
#include "core/io_error.h"
#include "core/logging.h"

namespace cgsr {

RunDir::RunDir(std::filesystem::path dir, bool own_log) : dir_(std::move(dir)), own_log_(own_log) {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  if (ec) throw file_system_error(dir_, ec.value(), "create the run directory");
  if (own_log_) attach_log_file(dir_ / "log.txt");
}

RunDir::~RunDir() {
  if (own_log_) finish_log_file();
}

void RunDir::write_config(const YAML::Node& resolved) const {
  write_file_atomic(file("config.yaml"), config::to_yaml(resolved));
}

void RunDir::write_results(const nlohmann::ordered_json& results) {
  // Inputs are checked for UTF-8 before a command starts (core/utf8.h); a name read from disk
  // that is not still must not cost the results at the very end, so it is replaced, not thrown.
  write_file_atomic(file("results.json"),
                    results.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n");
  for (const auto& step : after_results_) step();
  after_results_.clear();
}

void RunDir::after_results(std::function<void()> step) { after_results_.push_back(std::move(step)); }

std::filesystem::path default_run_dir(const std::string& command) {
  const std::time_t now = std::time(nullptr);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", std::localtime(&now));
  return std::filesystem::path("runs") / (command + "-" + stamp);
}

}  // namespace cgsr
