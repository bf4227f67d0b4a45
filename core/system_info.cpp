#include "core/system_info.h"

#include <ATen/Version.h>
#include <oneapi/tbb/version.h>
#include <opencv2/core/version.hpp>
#include <spdlog/version.h>
#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <fstream>
#include <thread>

#include "core/runtime.h"

#ifndef CGSR_VERSION
#define CGSR_VERSION "unknown"
#endif
#ifndef CGSR_BUILD_TYPE
#define CGSR_BUILD_TYPE "unknown"
#endif

namespace cgsr {
namespace {
// LibTorch does not export its capability query; its build summary names the level in use.
std::string torch_cpu_capability() {
  const std::string config = at::show_config();
  const std::string key = "CPU capability usage: ";
  const size_t at_key = config.find(key);
  if (at_key == std::string::npos) return "unknown";
  const size_t begin = at_key + key.size();
  return config.substr(begin, config.find('\n', begin) - begin);
}

std::string cpu_simd() {
  __builtin_cpu_init();
  if (__builtin_cpu_supports("avx512f")) return "AVX-512";
  if (__builtin_cpu_supports("avx2")) return "AVX2";
  if (__builtin_cpu_supports("avx")) return "AVX";
  if (__builtin_cpu_supports("sse4.2")) return "SSE4.2";
  return "baseline x86-64";
}
}  // namespace

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  const std::string key = "model name";
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(key, 0) != 0) continue;
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    const size_t begin = line.find_first_not_of(" \t", colon + 1);
    if (begin != std::string::npos) return line.substr(begin);
  }
  return "unknown CPU";
}

std::filesystem::path user_cache_dir() {
  const auto env = [](const char* name) -> std::string {
    const char* value = std::getenv(name);
    return value ? value : "";
  };
  if (const std::string dir = env("CGSR_CACHE_DIR"); !dir.empty()) return dir;
  if (const std::string dir = env("XDG_CACHE_HOME"); !dir.empty()) return std::filesystem::path(dir) / "cgsr";
  if (const std::string home = env("HOME"); !home.empty()) return std::filesystem::path(home) / ".cache" / "cgsr";
  return {};
}

nlohmann::ordered_json system_info() {
  nlohmann::ordered_json j;
  j["cgsr"] = CGSR_VERSION;
  j["build_type"] = CGSR_BUILD_TYPE;
  j["compiler"] = std::string("GCC ") + __VERSION__;
  j["libtorch"] = std::to_string(TORCH_VERSION_MAJOR) + "." + std::to_string(TORCH_VERSION_MINOR) + "." +
                  std::to_string(TORCH_VERSION_PATCH);
  j["opencv"] = CV_VERSION;
  j["tbb"] = TBB_runtime_version();
  j["spdlog"] = std::to_string(SPDLOG_VER_MAJOR) + "." + std::to_string(SPDLOG_VER_MINOR) + "." +
                std::to_string(SPDLOG_VER_PATCH);
  j["hardware_threads"] = std::thread::hardware_concurrency();
  j["threads"] = thread_count();
  j["cpu_simd"] = cpu_simd();
  j["torch_cpu_kernels"] = torch_cpu_capability();
  j["mkldnn"] = at::hasMKLDNN();
  j["openmp"] = at::get_parallel_info().find("OpenMP") != std::string::npos;
  return j;
}

}  // namespace cgsr
