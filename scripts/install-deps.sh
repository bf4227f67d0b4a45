#!/usr/bin/env bash
# Installs the Debian packages cgsr builds and runs with. Does nothing when all are present.
# Usage: scripts/install-deps.sh [--with-optional]
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libtorch-dev          # LibTorch 1.13 (CPU)
  libgloo-dev           # Gloo headers for LibTorch's c10d::ProcessGroupGloo (distributed/; the code is in libtorch)
  libopenblas0-openmp   # BLAS for LibTorch: without it libblas.so.3 is the reference BLAS, and every
                        # GEMM-based kernel (NCHW conv backward among them) runs ~10x slower
  libdnnl-dev           # oneDNN headers and CMake package (the fused inference path)
  libopencv-dev         # image I/O, OpenCV DNN for export verification
  libyaml-cpp-dev libtbb-dev libspdlog-dev libfmt-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libonnx-dev libprotobuf-dev protobuf-compiler   # ONNX export
  libzip-dev libstb-dev                           # pk3 archives, TGA textures
  libcairo2-dev fonts-dejavu-core                 # plots and image grids (core/canvas.h), their font
  python3-torch                                   # torch.jit.load check of TorchScript exports
)
# Optional: clang with libFuzzer for fuzz/ (-DCGSR_FUZZ=ON), Chromium for the test that opens a
# report page in a real browser, and the OpenArena game data (~400 MB)
# for configs/scenes/oa_*.yaml; the test suite runs without them (the browser test is then skipped).
if [ "${1:-}" = "--with-optional" ]; then
  packages+=(clang libclang-rt-dev chromium openarena-088-data openarena-data)
fi
# ONNX Runtime verification runs through the npm package onnxruntime-node; a machine
# whose Node.js does not come from Debian already has npm.
command -v npm >/dev/null 2>&1 || packages+=(nodejs npm)

# ONNX Runtime for export verification and `cgsr bench --onnx`: the CPU build ships inside the
# npm package; --ignore-scripts skips its install script (which would only fetch GPU binaries).
install_onnxruntime_node() {
  local dir
  dir="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)/tools/onnxruntime"
  if [ ! -f "$dir/node_modules/onnxruntime-node/package.json" ]; then
    echo "install-deps: npm ci --ignore-scripts in $dir"
    (cd "$dir" && npm ci --ignore-scripts --no-audit --no-fund)
  fi
}

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  install_onnxruntime_node
  exit 0
fi

echo "install-deps: installing ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps: run as root (or install the packages above with sudo apt-get install)" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}"
install_onnxruntime_node
