#pragma once
// The project's one exception type. It carries where a problem is (file, frame, key, line)
// so the CLI can print "error: <context>: <what>" and choose the exit code.

#include <stdexcept>
#include <string>

namespace cgsr {

enum class ErrorKind {
  User,      // bad input, config or data: exit code 2
  Internal,  // a bug or an environment failure: exit code 1
};

class Error : public std::runtime_error {
 public:
  Error(std::string context, const std::string& what, ErrorKind kind = ErrorKind::User);

  const std::string& context() const { return context_; }
  const std::string& message() const { return message_; }
  ErrorKind kind() const { return kind_; }

  // A copy of this error with an outer context prefixed, e.g. "frame 12" + "depth.png".
  Error within(const std::string& outer) const;

 private:
  std::string context_;
  std::string message_;
  ErrorKind kind_;
};

// Throws an internal error when a condition that the code itself guarantees does not hold.
#define CGSR_CHECK(cond, msg)                                                              \
  do {                                                                                     \
    if (!(cond)) throw ::cgsr::Error(__FILE__ ":" + std::to_string(__LINE__), (msg),        \
                                     ::cgsr::ErrorKind::Internal);                         \
  } while (0)

}  // namespace cgsr
