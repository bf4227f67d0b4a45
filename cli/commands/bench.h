#pragma once
// `cgsr bench`: inference latency of a network, here and in ONNX Runtime (the bench job:
// pipeline/bench.h). Here: its flags.

#include <CLI/CLI.hpp>

namespace cgsr::cli {

void setup_bench(CLI::App& app);

}  // namespace cgsr::cli
