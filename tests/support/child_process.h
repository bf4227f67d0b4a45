#pragma once
// Runs the real cgsr executable as a child process that a test can SIGKILL at a chosen moment
// (no destructors, no flushes: what a power cut, the OOM killer or `kill -9` leaves behind), for
// the kill/resume tests. Arguments are passed to execv as they are (no shell, no quoting);
// stdout and stderr go to files so a long run cannot fill a pipe and block.

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/cli_runner.h"

extern char** environ;

namespace cgsr::test {

class CgsrProcess {
 public:
  // Starts `cgsr args...`; stdout and stderr go to `<output_prefix>.out` and `<output_prefix>.err`.
  CgsrProcess(const std::vector<std::string>& args, const std::filesystem::path& output_prefix)
      : out_(output_prefix.string() + ".out"), err_(output_prefix.string() + ".err") {
    std::vector<std::string> words{CGSR_BINARY};
    words.insert(words.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int rc = posix_spawn(&pid_, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (rc != 0) throw std::runtime_error(std::string("posix_spawn ") + CGSR_BINARY + " failed");
  }
  ~CgsrProcess() {
    if (!reaped_) kill();
  }
  CgsrProcess(const CgsrProcess&) = delete;
  CgsrProcess& operator=(const CgsrProcess&) = delete;

  // True while the child has not exited (reaps it when it has).
  bool running() {
    if (reaped_) return false;
    if (::waitpid(pid_, &status_, WNOHANG) == pid_) reaped_ = true;
    return !reaped_;
  }

  // Polls `condition` until it holds (true), or the child exits or `timeout` passes (false). A
  // condition that holds at the moment the child exits still counts.
  bool wait_for(const std::function<bool()>& condition, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      if (condition()) return true;
      if (!running()) return condition();
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
  }

  // SIGKILL, then reap. True when the child was still running and died from the signal (false
  // when it had exited on its own first).
  bool kill() {
    if (!reaped_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status_, 0);
      reaped_ = true;
    }
    return WIFSIGNALED(status_) && WTERMSIG(status_) == SIGKILL;
  }

  // Waits for the child to exit; its exit code, or -1 when a signal ended it.
  int wait() {
    if (!reaped_) {
      ::waitpid(pid_, &status_, 0);
      reaped_ = true;
    }
    return WIFEXITED(status_) ? WEXITSTATUS(status_) : -1;
  }

  pid_t pid() const { return pid_; }
  std::string out() const { return slurp(out_); }
  std::string err() const { return slurp(err_); }

 private:
  std::string out_, err_;
  pid_t pid_ = -1;
  int status_ = 0;
  bool reaped_ = false;
};

// Runs `cgsr args...` to the end, like run_cgsr() but without a shell.
inline CliResult run_cgsr_args(const std::vector<std::string>& args, const std::filesystem::path& output_prefix) {
  CgsrProcess process(args, output_prefix);
  CliResult r;
  r.exit_code = process.wait();
  r.out = process.out();
  r.err = process.err();
  return r;
}

}  // namespace cgsr::test
