#include "cli/failure.h"

#include <c10/util/Exception.h>
#include <spdlog/spdlog.h>

#include <cstdio>
#include <new>
#include <opencv2/core.hpp>
#include <string>

#include "core/error.h"

namespace cgsr::cli {

namespace {
constexpr const char* kOutOfMemory =
    "out of memory: the sizes asked for (batch_size, patch_size, an input or render resolution) need more "
    "memory than this machine can give; lower them";

int user(const std::string& message) {
  std::fprintf(stderr, "error: %s\n", message.c_str());
  return 2;
}

int internal(const std::string& message) {
  std::fprintf(stderr, "error: internal: %s\n", message.c_str());
  return 1;
}

bool says_out_of_memory(const std::string& message) {
  return message.find("not enough memory") != std::string::npos ||
         message.find("can't allocate memory") != std::string::npos ||
         message.find("Insufficient memory") != std::string::npos;
}
}  // namespace

int report_failure(const std::exception_ptr& error, bool verbose) {
  try {
    std::rethrow_exception(error);
  } catch (const Error& e) {
    spdlog::debug("{}", e.what());
    std::fprintf(stderr, "error: %s\n", e.what());
    return e.kind() == ErrorKind::User ? 2 : 1;
  } catch (const std::bad_alloc&) {
    return user(kOutOfMemory);
  } catch (const c10::Error& e) {
    // what() carries a backtrace of 40 frames: for developers, under --verbose.
    const std::string brief = e.what_without_backtrace();
    if (says_out_of_memory(brief)) return user(kOutOfMemory);
    return internal(verbose ? e.what() : brief);
  } catch (const cv::Exception& e) {
    if (e.code == cv::Error::StsNoMem || says_out_of_memory(e.msg)) return user(kOutOfMemory);
    return internal(e.what());
  } catch (const std::exception& e) {
    return internal(e.what());
  } catch (...) {
    return internal("an exception of an unknown type");
  }
}

}  // namespace cgsr::cli
