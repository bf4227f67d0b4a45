#!/usr/bin/env bash
# The speed benchmark: in one run, on the same machine in the same minutes, PAN x2 at an LR size
# through every path cgsr has (LibTorch NCHW and channels-last, the fused oneDNN path), the same
# network exported and run by ONNX Runtime, PyTorch eager in both layouts (python3-torch), and
# the training step in cgsr and PyTorch. Prints a table of medians and the ratios the speed
# targets are about. The fused path also runs in int8 and bf16 (int8 calibrated on the timed input:
# latency does not depend on the scales); with --data DIR (a rendered data set), PAN x2 is also
# exported as an int8 QDQ file calibrated on its frames and timed in ONNX Runtime. Run from the repository root after building (cmake --build build).
# The training step is timed in --train-rounds rounds, cgsr's and PyTorch's processes taking
# turns, and each side's median round is reported (one round of each is at the mercy of whatever
# else the machine runs in that minute).
#
#   bash bench/speed.sh [--input 320x240] [--runs 7] [--train-rounds 5] [--threads 2] [--build build] [--data DIR]
set -euo pipefail

input=320x240
runs=7
train_rounds=5
threads=2
build=build
data=
while [ $# -gt 0 ]; do
  case "$1" in
    --input) input="$2"; shift 2 ;;
    --runs) runs="$2"; shift 2 ;;
    --train-rounds) train_rounds="$2"; shift 2 ;;
    --threads) threads="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    --data) data="$2"; shift 2 ;;
    *) echo "usage: bench/speed.sh [--input WxH] [--runs N] [--train-rounds N] [--threads N] [--build DIR] [--data DIR]" >&2; exit 2 ;;
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
if [ -n "$data" ]; then
  "$cgsr" export --model pan --scale 2 --format onnx --input "$input" --out "$work/pan_int8.onnx" --seed 1 \
    --precision int8 --data "$data" >/dev/null
fi

echo "speed.sh: timing inference ($runs runs each)" >&2
for layout in nchw nhwc; do
  "$cgsr" bench --model pan --scale 2 --input "$input" --engine libtorch --layout "$layout" --set runs="$runs" \
    --threads "$threads" --json >"$work/bench_$layout.json"
done
# The fused path (each precision) and ONNX Runtime in one command: their ratios are of the same minutes.
"$cgsr" bench --onnx "$work/pan.onnx" --input "$input" --engine fused --precision fp32 int8 bf16 --set runs="$runs" \
  --threads "$threads" --json >"$work/bench_fused.json"
if [ -n "$data" ]; then
  "$cgsr" bench --onnx "$work/pan_int8.onnx" --input "$input" --engine fused --precision int8 --set runs="$runs" \
    --threads "$threads" --json >"$work/bench_int8.json"
fi
echo "speed.sh: PyTorch inference" >&2
"$python" "$(dirname "$0")/pytorch_reference.py" --input "$input" --runs "$runs" --threads "$threads" \
  --torchscript "$work/pan.pt" --only inference >"$work/pytorch.json"
for round in $(seq "$train_rounds"); do
  echo "speed.sh: training step, round $round/$train_rounds (cgsr, then PyTorch)" >&2
  "$build/bench/bench_training_step" --threads "$threads" >"$work/train_cgsr_$round.json"
  "$python" "$(dirname "$0")/pytorch_reference.py" --threads "$threads" --only training >"$work/train_pytorch_$round.json"
done

"$python" - "$work" "$train_rounds" <<'EOF'
import json, sys, os
w, rounds = sys.argv[1], int(sys.argv[2])
load = lambda name: json.load(open(os.path.join(w, name)))
ms = {f"cgsr libtorch {l}": load(f"bench_{l}.json")["results"][0]["median_ms"] for l in ("nchw", "nhwc")}
fused = load("bench_fused.json")["results"]
ms["cgsr fused"] = fused[0]["median_ms"]
ms["cgsr fused int8"] = fused[1]["median_ms"]
ms["cgsr fused bf16"] = fused[2]["median_ms"]
ms["onnxruntime"] = fused[3]["median_ms"]
int8_file = os.path.join(w, "bench_int8.json")
if os.path.exists(int8_file):
    int8 = json.load(open(int8_file))["results"]
    ms["cgsr fused int8 (2nd run)"] = int8[0]["median_ms"]
    ms["onnxruntime int8 (QDQ)"] = int8[1]["median_ms"]
py = load("pytorch.json")
ms["pytorch eager nchw"] = py["inference_ms"]["nchw"]
ms["pytorch eager channels-last"] = py["inference_ms"]["nhwc"]
# Each side's median round, per layout, with the phases of that round.
def median_round(prefix, rate_key, phase_key):
    runs = [load(f"{prefix}_{r}.json") for r in range(1, rounds + 1)]
    out = {}
    for layout in ("nchw", "nhwc"):
        ranked = sorted(runs, key=lambda run: run[rate_key][layout])
        mid = ranked[len(ranked) // 2]
        out[layout] = (mid[rate_key][layout], mid[phase_key][layout])
    return out
cgsr_train = median_round("train_cgsr", "train_steps_per_second", "ms_per_step")
torch_train = median_round("train_pytorch", "train_steps_per_second", "train_ms_per_step")
print(f"PAN x2 forward at {py['input']}, {py['threads']} threads (median ms)")
for name, v in ms.items():
    print(f"  {name:30s} {v:10.1f}")
print(f"  (PyTorch's weights are the exported file's: max |eager - export| = {py['max_abs_diff_vs_export']:.2e})")
print(f"training step, PAN x2, batch 4 of 24x24 LR patches (steps/s, median of {rounds} rounds; "
      "ms per step: forward+loss / backward / clip / optimizer)")
def train_row(name, entry):
    rate, phase_ms = entry
    phases = " / ".join(f"{phase_ms[k]:.1f}" for k in ("forward_and_loss", "backward", "clip", "optimizer"))
    print(f"  {name:30s} {rate:10.2f}    {phases}")
train_row("cgsr nchw", cgsr_train["nchw"])
train_row("cgsr channels-last", cgsr_train["nhwc"])
train_row("pytorch nchw", torch_train["nchw"])
train_row("pytorch channels-last", torch_train["nhwc"])
print("ratios")
print(f"  onnxruntime ms / cgsr fused ms          {ms['onnxruntime'] / ms['cgsr fused']:.2f}x  (target >= 1.0)")
print(f"  onnxruntime ms / cgsr libtorch channels-last ms  {ms['onnxruntime'] / ms['cgsr libtorch nhwc']:.2f}x")
print(f"  cgsr fused fp32 ms / cgsr fused int8 ms  {ms['cgsr fused'] / ms['cgsr fused int8']:.2f}x  (target >= 2.0)")
print(f"  cgsr fused fp32 ms / cgsr fused bf16 ms  {ms['cgsr fused'] / ms['cgsr fused bf16']:.2f}x")
if "onnxruntime int8 (QDQ)" in ms:
    print(f"  onnxruntime int8 ms / cgsr fused int8 ms  "
          f"{ms['onnxruntime int8 (QDQ)'] / ms['cgsr fused int8 (2nd run)']:.2f}x  (same command)")
print(f"  cgsr channels-last / pytorch channels-last training  "
      f"{cgsr_train['nhwc'][0] / torch_train['nhwc'][0]:.2f}x  (target >= 1.0)")
EOF
