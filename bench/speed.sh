#!/usr/bin/env bash
# The speed benchmark: in one run, on the same machine in the same minutes, PAN x2 at an LR size
# through every path cgsr has (LibTorch NCHW and channels-last, the fused oneDNN path), the same
# network exported and run by ONNX Runtime, PyTorch eager in both layouts (python3-torch), and
# the training step in cgsr and PyTorch. Prints a table of medians and the ratios the speed
# targets are about. Run from the repository root after building (cmake --build build).
#
#   bash bench/speed.sh [--input 320x240] [--runs 7] [--threads 2] [--build build]
set -euo pipefail

input=320x240
runs=7
threads=2
build=build
while [ $# -gt 0 ]; do
  case "$1" in
    --input) input="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    *) echo "usage: bench/speed.sh [--input WxH] [--runs N] [--threads N] [--build DIR]" >&2; exit 2 ;;
  esac
done
cgsr="$build/cgsr"
[ -x "$cgsr" ] || { echo "speed.sh: $cgsr not built (cmake --build $build)" >&2; exit 2; }
python=/usr/bin/python3  # Debian's, with python3-torch
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

echo "speed.sh: exporting PAN x2 at $input (ONNX and TorchScript)" >&2
"$cgsr" export --model pan --scale 2 --format onnx --input "$input" --out "$work/pan.onnx" --seed 1 >/dev/null
"$cgsr" export --model pan --scale 2 --format torchscript --input "$input" --out "$work/pan.pt" --seed 1 >/dev/null

echo "speed.sh: timing inference ($runs runs each)" >&2
for layout in nchw nhwc; do
  "$cgsr" bench --model pan --scale 2 --input "$input" --engine libtorch --layout "$layout" --set runs="$runs" \
    --threads "$threads" --json >"$work/bench_$layout.json"
done
# The fused path and ONNX Runtime in one command: their ratio is of the same minutes.
"$cgsr" bench --onnx "$work/pan.onnx" --input "$input" --engine fused --set runs="$runs" --threads "$threads" \
  --json >"$work/bench_fused.json"
echo "speed.sh: PyTorch (inference and training step)" >&2
"$python" "$(dirname "$0")/pytorch_reference.py" --input "$input" --runs "$runs" --threads "$threads" \
  --torchscript "$work/pan.pt" >"$work/pytorch.json"
echo "speed.sh: cgsr training step" >&2
"$build/bench/bench_training_step" --threads "$threads" >"$work/train.json"

"$python" - "$work" <<'EOF'
import json, sys, os
w = sys.argv[1]
load = lambda name: json.load(open(os.path.join(w, name)))
ms = {f"cgsr libtorch {l}": load(f"bench_{l}.json")["results"][0]["median_ms"] for l in ("nchw", "nhwc")}
fused = load("bench_fused.json")["results"]
ms["cgsr fused"] = fused[0]["median_ms"]
ms["onnxruntime"] = fused[1]["median_ms"]
py = load("pytorch.json")
ms["pytorch eager nchw"] = py["inference_ms"]["nchw"]
ms["pytorch eager channels-last"] = py["inference_ms"]["nhwc"]
train = load("train.json")["train_steps_per_second"]
print(f"PAN x2 forward at {py['input']}, {py['threads']} threads (median ms)")
for name, v in ms.items():
    print(f"  {name:30s} {v:10.1f}")
print(f"  (PyTorch's weights are the exported file's: max |eager - export| = {py['max_abs_diff_vs_export']:.2e})")
print("training step, PAN x2, batch 4 of 24x24 LR patches (steps/s)")
print(f"  {'cgsr nchw':30s} {train['nchw']:10.2f}")
print(f"  {'cgsr channels-last':30s} {train['nhwc']:10.2f}")
print(f"  {'pytorch nchw':30s} {py['train_steps_per_second']['nchw']:10.2f}")
print(f"  {'pytorch channels-last':30s} {py['train_steps_per_second']['nhwc']:10.2f}")
print("ratios")
print(f"  onnxruntime ms / cgsr fused ms          {ms['onnxruntime'] / ms['cgsr fused']:.2f}x  (target >= 1.0)")
print(f"  onnxruntime ms / cgsr libtorch channels-last ms  {ms['onnxruntime'] / ms['cgsr libtorch nhwc']:.2f}x")
print(f"  cgsr channels-last / pytorch channels-last training  {train['nhwc'] / py['train_steps_per_second']['nhwc']:.2f}x  (target >= 1.0)")
EOF
