// The driver of a fuzz target when it is built without libFuzzer (GCC builds, and so CI): runs
// the target on every seed file and on deterministic mutations of each (bytes flipped, fields
// overwritten with extreme values, numbers replaced, truncations, deletions, duplications).
// A target returns normally for every input, so an escaped exception, a crash or, in the
// sanitizer build, any ASan/UBSan report fails the run. On an escaped exception or a fatal
// signal the input is saved as ./fuzz-crash-<target> so it can be replayed: fuzz_x FILE.
//
//   fuzz_config [--mutations N] SEED_FILE_OR_DIR...
//
// The same targets built with -DCGSR_FUZZ=ON (clang) are coverage-guided libFuzzer binaries.

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <exception>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace {
namespace fs = std::filesystem;
using Bytes = std::vector<uint8_t>;

// The input being run, saved by the crash handlers below.
const Bytes* g_input = nullptr;
std::string g_crash_file, g_crash_note;

void save_input() {
  if (!g_input) return;
  const int fd = ::open(g_crash_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd >= 0) {
    (void)!::write(fd, g_input->data(), g_input->size());
    ::close(fd);
  }
  (void)!::write(2, g_crash_note.data(), g_crash_note.size());
}

void on_signal(int sig) {
  save_input();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

void on_terminate() {
  if (const auto e = std::current_exception()) {
    try {
      std::rethrow_exception(e);
    } catch (const std::exception& ex) {
      std::fprintf(stderr, "uncaught exception: %s\n", ex.what());
    } catch (...) {
      std::fprintf(stderr, "uncaught exception of unknown type\n");
    }
  }
  save_input();
  std::_Exit(1);
}

Bytes read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::vector<fs::path> seed_files(const std::vector<std::string>& args) {
  std::vector<fs::path> out;
  for (const auto& a : args) {
    if (fs::is_directory(a)) {
      for (const auto& e : fs::recursive_directory_iterator(a))
        if (e.is_regular_file()) out.push_back(e.path());
    } else if (fs::is_regular_file(a)) {
      out.push_back(a);
    } else {
      std::fprintf(stderr, "%s: no such seed file or folder\n", a.c_str());
      std::exit(2);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

// One mutation of `b`; which one, and where, is drawn from `rng`.
Bytes mutate(Bytes b, std::mt19937_64& rng) {
  auto pick = [&](size_t n) { return n == 0 ? size_t{0} : static_cast<size_t>(rng() % n); };
  switch (rng() % 7) {
    case 0: {  // flip a few bytes
      const int flips = 1 + static_cast<int>(rng() % 8);
      for (int i = 0; i < flips && !b.empty(); ++i) b[pick(b.size())] ^= static_cast<uint8_t>(1 + rng() % 255);
      break;
    }
    case 1: {  // an aligned 32-bit field becomes an extreme integer or float
      static const uint32_t nasty[] = {0u, 1u, 0xffffffffu, 0x7fffffffu, 0x80000000u, 0x7fc00000u /* NaN */,
                                       0x7f800000u /* inf */, 0x00010000u, 0xffff0000u};
      if (b.size() >= 4) std::memcpy(&b[pick(b.size() / 4) * 4], &nasty[rng() % std::size(nasty)], 4);
      break;
    }
    case 2: {  // a number in text becomes an extreme one
      static const char* numbers[] = {"-1", "0", "1e308", "-1e308", "nan", ".inf", "99999999999999999999",
                                      "2147483648", "1e-320", "0x7fffffff"};
      std::vector<size_t> digits;
      for (size_t i = 0; i < b.size(); ++i)
        if (b[i] >= '0' && b[i] <= '9' && (i == 0 || b[i - 1] < '0' || b[i - 1] > '9')) digits.push_back(i);
      if (digits.empty()) break;
      const size_t at = digits[pick(digits.size())];
      size_t end = at;
      while (end < b.size() && ((b[end] >= '0' && b[end] <= '9') || b[end] == '.')) ++end;
      const std::string n = numbers[rng() % std::size(numbers)];
      b.erase(b.begin() + at, b.begin() + end);
      b.insert(b.begin() + at, n.begin(), n.end());
      break;
    }
    case 3:  // truncate
      b.resize(pick(b.size()));
      break;
    case 4: {  // delete a chunk
      const size_t at = pick(b.size()), n = std::min(b.size() - at, 1 + pick(64));
      b.erase(b.begin() + at, b.begin() + at + n);
      break;
    }
    case 5: {  // duplicate a chunk in place
      const size_t at = pick(b.size()), n = std::min(b.size() - at, 1 + pick(64));
      const Bytes chunk(b.begin() + at, b.begin() + at + n);
      b.insert(b.begin() + at, chunk.begin(), chunk.end());
      break;
    }
    default: {  // insert random bytes
      const size_t at = pick(b.size() + 1), n = 1 + pick(16);
      Bytes noise(n);
      for (auto& c : noise) c = static_cast<uint8_t>(rng());
      b.insert(b.begin() + at, noise.begin(), noise.end());
      break;
    }
  }
  return b;
}

}  // namespace

int main(int argc, char** argv) {
  int mutations = 100;
  std::vector<std::string> args;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--mutations") == 0 && i + 1 < argc) {
      mutations = std::atoi(argv[++i]);
    } else {
      args.push_back(argv[i]);
    }
  }
  const auto seeds = seed_files(args);
  if (seeds.empty()) {
    std::fprintf(stderr, "usage: %s [--mutations N] SEED_FILE_OR_DIR...\n", argv[0]);
    return 2;
  }
  g_crash_file = "fuzz-crash-" + fs::path(argv[0]).filename().string();
  std::set_terminate(on_terminate);
  for (int sig : {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL}) std::signal(sig, on_signal);
  size_t inputs = 0;
  auto run = [&](const Bytes& input, const fs::path& seed, int mutation) {
    g_input = &input;
    g_crash_note = "input saved as " + (fs::current_path() / g_crash_file).string() + " (seed " + seed.string() +
                   (mutation < 0 ? "" : ", mutation " + std::to_string(mutation)) + ")\n";
    LLVMFuzzerTestOneInput(input.data(), input.size());
    g_input = nullptr;
    ++inputs;
  };
  for (size_t s = 0; s < seeds.size(); ++s) {
    const Bytes seed = read_bytes(seeds[s]);
    std::mt19937_64 rng(0x9E3779B97F4A7C15ULL * (s + 1));
    run(seed, seeds[s], -1);
    for (int m = 0; m < mutations; ++m) {
      // A quarter of the inputs get a second mutation on top of the first, as a fuzzer stacks them.
      Bytes input = mutate(seed, rng);
      if (rng() % 4 == 0) input = mutate(std::move(input), rng);
      run(input, seeds[s], m);
    }
  }
  std::printf("%zu inputs (%zu seed files, %d mutations each): every one parsed or was rejected cleanly\n", inputs,
              seeds.size(), mutations);
  return 0;
}
