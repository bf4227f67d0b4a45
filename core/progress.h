#pragma once
// Progress for long loops (render, train, search, eval): a bar with rate and ETA on a terminal,
// periodic plain log lines otherwise (CI, pipes). Thread-safe: workers may call advance().

#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace cgsr {

class Progress {
 public:
  Progress(std::string label, int64_t total, int64_t start = 0);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void advance(int64_t n = 1);
  void set_status(const std::string& status);  // e.g. "loss 0.012", shown after the counts
  void finish();

  // Forces the plain-line mode (tests, or when the caller knows the output is a log).
  static void set_interactive(bool interactive);

 private:
  void report(bool final);
  std::string line(double elapsed_s) const;

  std::string label_;
  int64_t total_;
  int64_t start_;
  std::atomic<int64_t> done_;
  std::string status_;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point began_, last_report_;
  bool interactive_;
  bool finished_ = false;
};

}  // namespace cgsr
