#pragma once
// How a failed command is told: its message and exit code. User mistakes and the machine's limits
// (a full disk, a read-only folder, memory for the sizes asked for) exit 2 with the fix; anything
// else is internal, exit 1, with LibTorch's backtrace only under --verbose.

#include <exception>

namespace cgsr::cli {

// Prints "error: ..." for the exception in `error` and returns the exit code.
int report_failure(const std::exception_ptr& error, bool verbose);

}  // namespace cgsr::cli
