#include "core/progress.h"

#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdio>

namespace cgsr {
namespace {
int& interactive_override() {
  static int value = -1;  // -1: detect
  return value;
}
std::string clock_text(double seconds) {
  const int s = static_cast<int>(seconds + 0.5);
  char buf[32];
  if (s >= 3600) std::snprintf(buf, sizeof buf, "%d:%02d:%02d", s / 3600, s / 60 % 60, s % 60);
  else std::snprintf(buf, sizeof buf, "%d:%02d", s / 60, s % 60);
  return buf;
}
}  // namespace

void Progress::set_interactive(bool interactive) { interactive_override() = interactive ? 1 : 0; }

Progress::Progress(std::string label, int64_t total, int64_t start)
    : label_(std::move(label)),
      total_(total),
      start_(start),
      done_(start),
      began_(std::chrono::steady_clock::now()),
      last_report_(began_) {
  interactive_ = interactive_override() >= 0 ? interactive_override() == 1 : ::isatty(STDERR_FILENO) == 1;
}

Progress::~Progress() { finish(); }

void Progress::advance(int64_t n) {
  done_ += n;
  report(false);
}

void Progress::set_status(const std::string& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  status_ = status;
}

void Progress::finish() {
  if (finished_) return;
  report(true);
  finished_ = true;
}

std::string Progress::line(double elapsed) const {
  const int64_t done = done_.load();
  const double rate = elapsed > 0 ? (done - start_) / elapsed : 0.0;
  const double eta = rate > 0 && total_ > done ? (total_ - done) / rate : 0.0;
  char counts[160];
  std::snprintf(counts, sizeof counts, "%lld/%lld %.2f/s elapsed %s ETA %s", static_cast<long long>(done),
                static_cast<long long>(total_), rate, clock_text(elapsed).c_str(), clock_text(eta).c_str());
  std::string text = label_ + " ";
  if (interactive_) {
    const int width = 24;
    const int filled = total_ > 0 ? static_cast<int>(width * std::min<int64_t>(done, total_) / total_) : 0;
    text += "[" + std::string(filled, '#') + std::string(width - filled, ' ') + "] ";
  }
  text += counts;
  if (!status_.empty()) text += "  " + status_;
  return text;
}

void Progress::report(bool final) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  const auto now = std::chrono::steady_clock::now();
  const double since_last = std::chrono::duration<double>(now - last_report_).count();
  // A terminal redraws ten times a second; a log gets a line every ten seconds.
  if (!final && since_last < (interactive_ ? 0.1 : 10.0)) return;
  last_report_ = now;
  const std::string text = line(std::chrono::duration<double>(now - began_).count());
  if (interactive_) {
    std::fprintf(stderr, "\r\033[2K%s%s", text.c_str(), final ? "\n" : "");
    std::fflush(stderr);
  } else {
    spdlog::info("{}", text);
  }
}

}  // namespace cgsr
