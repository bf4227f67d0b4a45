#include "models/memory_layout.h"

#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/file.h>
#include <torch/torch.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <memory>
#include <utility>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/runtime.h"
#include "core/system_info.h"
#include "core/timing.h"

namespace cgsr {

const std::vector<std::string>& EnumNames<MemoryLayout>::names() {
  static const std::vector<std::string> names = {"auto", "nchw", "nhwc"};
  return names;
}

torch::Tensor to_layout(const torch::Tensor& t, MemoryLayout layout) {
  if (!t.defined() || t.dim() != 4 || layout == MemoryLayout::Auto) return t;
  return t.contiguous(layout == MemoryLayout::Nhwc ? torch::MemoryFormat::ChannelsLast
                                                   : torch::MemoryFormat::Contiguous);
}

void set_parameter_layout(torch::nn::Module& module, MemoryLayout layout) {
  if (layout == MemoryLayout::Auto) return;
  torch::NoGradGuard no_grad;
  const auto relay = [&](torch::Tensor& t) {
    if (t.defined() && t.dim() == 4) {
      const auto laid = to_layout(t, layout);
      if (!laid.is_same(t)) t.set_data(laid);
    }
  };
  for (auto& p : module.parameters()) {
    relay(p);
    if (p.grad().defined() && p.grad().dim() == 4) p.mutable_grad() = to_layout(p.grad(), layout);
  }
  for (auto& b : module.buffers()) relay(b);
}

namespace {
namespace fs = std::filesystem;

std::mutex& layouts_mutex() {
  static std::mutex mutex;
  return mutex;
}
std::map<std::string, MemoryLayout>& answers() {  // this process's, per key
  static std::map<std::string, MemoryLayout> chosen;
  return chosen;
}
fs::path& record_file() {  // the innermost LayoutRecordScope's
  static fs::path file;
  return file;
}

// A layouts.json: key -> "nchw" or "nhwc". A malformed run record is an error (it decides what a
// rerun does); a malformed machine cache is ignored with a warning and measured again.
std::map<std::string, MemoryLayout> read_layouts(const fs::path& file, bool strict) {
  std::map<std::string, MemoryLayout> out;
  std::error_code ec;
  if (file.empty() || !fs::exists(file, ec)) return out;
  try {
    const auto j = nlohmann::json::parse(read_file(file));
    if (!j.is_object()) throw std::runtime_error("not a JSON object");
    for (const auto& [key, value] : j.items()) {
      const auto layout = enum_from_name<MemoryLayout>(value.get<std::string>());
      if (layout == MemoryLayout::Auto) throw std::runtime_error("'" + key + "': auto is not a layout");
      out[key] = layout;
    }
  } catch (const std::exception& e) {
    if (strict) throw Error(file.string(), std::string("malformed record of memory layouts: ") + e.what());
    spdlog::warn("{}: ignored, malformed ({}); layouts are measured again", file.string(), e.what());
    out.clear();
  }
  return out;
}

void write_layouts(const fs::path& file, const std::map<std::string, MemoryLayout>& layouts) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const auto& [key, layout] : layouts) j[key] = enum_name(layout);
  write_file_atomic(file, j.dump(2) + "\n");
}

// An exclusive flock on a file while alive; the system releases it if the process dies.
class FileLock {
 public:
  explicit FileLock(const fs::path& path) : fd_(::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644)) {
    if (fd_ < 0) throw Error(path.string(), std::string("cannot open the lock file: ") + std::strerror(errno));
    while (::flock(fd_, LOCK_EX) != 0)
      if (errno != EINTR) {
        const int error = errno;
        ::close(fd_);
        throw Error(path.string(), std::string("cannot lock: ") + std::strerror(error));
      }
  }
  ~FileLock() {
    ::flock(fd_, LOCK_UN);
    ::close(fd_);
  }
  FileLock(const FileLock&) = delete;
  FileLock& operator=(const FileLock&) = delete;

 private:
  int fd_;
};

// Steps 3 and 4 of measured_layout; `how` says which one answered.
MemoryLayout cached_or_measured(const std::string& key, const std::function<void(MemoryLayout)>& run, int rounds,
                                std::string& how) {
  fs::path cache = layout_cache_file();
  std::unique_ptr<FileLock> lock;
  if (!cache.empty()) {
    try {
      fs::create_directories(cache.parent_path());
      lock = std::make_unique<FileLock>(cache.string() + ".lock");
    } catch (const std::exception& e) {
      spdlog::warn("no cache of memory layouts ({}): this process measures its own", e.what());
      cache.clear();
    }
  }
  auto cached = read_layouts(cache, /*strict=*/false);
  const std::string machine_key = machine_layout_key(key);
  if (const auto it = cached.find(machine_key); it != cached.end()) {
    how = "cached for this machine in " + cache.string();
    return it->second;
  }
  const auto stats = measure_latency_interleaved({[&] { run(MemoryLayout::Nchw); }, [&] { run(MemoryLayout::Nhwc); }},
                                                 /*warmup=*/1, rounds);
  const MemoryLayout best = stats[1].median_ms < stats[0].median_ms ? MemoryLayout::Nhwc : MemoryLayout::Nchw;
  how = fmt::format("nchw {:.1f} ms, nhwc {:.1f} ms, median of {}", stats[0].median_ms, stats[1].median_ms, rounds);
  if (!cache.empty()) {
    cached[machine_key] = best;
    try {
      write_layouts(cache, cached);
      how += "; cached for this machine in " + cache.string();
    } catch (const std::exception& e) {
      spdlog::warn("cannot cache the memory layout: {}", e.what());
    }
  }
  return best;
}
}  // namespace

MemoryLayout measured_layout(const std::string& key, const std::function<void(MemoryLayout)>& run, int rounds) {
  std::lock_guard<std::mutex> guard(layouts_mutex());
  if (const auto it = answers().find(key); it != answers().end()) return it->second;
  const fs::path record = record_file();
  auto recorded = read_layouts(record, /*strict=*/true);
  MemoryLayout chosen = MemoryLayout::Nchw;
  std::string how;
  if (const auto it = recorded.find(key); it != recorded.end()) {
    chosen = it->second;
    how = "as recorded in " + record.string();
  } else {
    chosen = cached_or_measured(key, run, rounds, how);
    if (!record.empty()) {
      recorded[key] = chosen;
      write_layouts(record, recorded);
    }
  }
  spdlog::info("layout for {}: {} ({})", key, enum_name(chosen), how);
  answers()[key] = chosen;
  return chosen;
}

LayoutRecordScope::LayoutRecordScope(std::filesystem::path file) {
  std::lock_guard<std::mutex> guard(layouts_mutex());
  outer_ = std::exchange(record_file(), std::move(file));
}

LayoutRecordScope::~LayoutRecordScope() {
  std::lock_guard<std::mutex> guard(layouts_mutex());
  record_file() = outer_;
}

std::filesystem::path layout_cache_file() {
  const fs::path dir = user_cache_dir();
  return dir.empty() ? fs::path() : dir / "layouts.json";
}

std::string machine_layout_key(const std::string& key) {
  return key + " | " + std::to_string(thread_count()) + " threads | " + cpu_model();
}

void forget_measured_layouts() {
  std::lock_guard<std::mutex> guard(layouts_mutex());
  answers().clear();
}

}  // namespace cgsr
