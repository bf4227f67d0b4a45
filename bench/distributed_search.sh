#!/usr/bin/env bash
# A search as one process against the same search as two processes on this machine (issue 17,
# docs/distributed.md): configs/search/compare.yaml's candidate training on the quickstart's
# CG-enhanced network and data, with a fixed memory layout and a short final training. Three runs:
#   1 process  x 2 threads   (the machine's two cores in one process)
#   1 process  x 1 thread    (the reference of the identity check)
#   2 processes x 1 thread   (--world-size 2 on 127.0.0.1)
# and prints each run's wall time, load average before it, and whether the 2-process history and
# pick equal the 1-thread reference's. Run from the repository root after building and after
# `cgsr run --config configs/quickstart.yaml`.
#
#   bash bench/distributed_search.sh [--out runs/distributed-search] [--build build] [--generations 2]
#                                    [--candidate-steps 60]   (training steps of each candidate)
set -euo pipefail

out=runs/distributed-search
build=build
generations=2
candidate_steps=60
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    --generations) generations="$2"; shift 2 ;;
    --candidate-steps) candidate_steps="$2"; shift 2 ;;
    *) echo "usage: bench/distributed_search.sh [--out DIR] [--build DIR] [--generations N] [--candidate-steps N]" >&2
       exit 2 ;;
  esac
done
cgsr="$build/cgsr"
[ -x "$cgsr" ] || { echo "distributed_search.sh: $cgsr not built (cmake --build $build)" >&2; exit 2; }
rm -rf "$out"
mkdir -p "$out"
args=(search --config configs/search/compare.yaml --seed 1 --set "search.generations=$generations"
      --set "candidate.schedule.steps=$candidate_steps" --set candidate.schedule.layout=nhwc --set final.steps=2 --set final.layout=nhwc)
port=$((20000 + $$ % 20000))

run() {  # name, then the command; prints "name seconds load"
  local name="$1"; shift
  local load start end
  load=$(cut -d' ' -f1 /proc/loadavg)
  start=$(date +%s.%N)
  "$@"
  end=$(date +%s.%N)
  printf '%-26s %7.1f s   (load average before: %s)\n' "$name" "$(echo "$end - $start" | bc)" "$load"
}

{
  run "1 process x 2 threads" "$cgsr" "${args[@]}" --threads 2 --out "$out/one-2threads" 2>"$out/one-2threads.log"
  run "1 process x 1 thread" "$cgsr" "${args[@]}" --threads 1 --out "$out/one-1thread" 2>"$out/one-1thread.log"
  two() {
    "$cgsr" "${args[@]}" --threads 1 --out "$out/two" --world-size 2 --rank 1 --store "127.0.0.1:$port" \
      2>"$out/two-rank1.log" &
    local rank1=$!
    "$cgsr" "${args[@]}" --threads 1 --out "$out/two" --world-size 2 --rank 0 --store "127.0.0.1:$port" \
      2>"$out/two-rank0.log"
    wait "$rank1"
  }
  run "2 processes x 1 thread" two
} | tee "$out/times.txt"

python3 - "$out" <<'PY' | tee -a "$out/times.txt"
import json, sys
out = sys.argv[1]
def history(run):
    lines = [json.loads(l) for l in open(f"{out}/{run}/history.jsonl")]
    for l in lines: l["score"].pop("train_seconds")
    return lines
a, b = history("one-1thread"), history("two")
ra, rb = (json.load(open(f"{out}/{r}/results.json")) for r in ("one-1thread", "two"))
worker = json.load(open(f"{out}/two/rank1/results.json"))
print(f"candidates: {ra['candidates']}; rank 1 trained {worker['candidates_trained']} of them")
print("2-process history equals the 1-process one:", a == b, f"({len(a)} lines)")
print("same pick:", ra["pick"]["spec_yaml"] == rb["pick"]["spec_yaml"],
      f"({ra['pick']['spec']}, {ra['pick']['score']['params']} params)")
PY
