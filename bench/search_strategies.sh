#!/usr/bin/env bash
# Evolution against random search at equal budget (issue 17): both strategies run the same
# config (configs/search/compare.yaml: same candidate training, same number of candidates) for
# each seed; the table gives, per run, the smallest candidate within the PSNR tolerance of the
# parent (the pick rule) and the Pareto front of size against validation PSNR. Runs that finished
# are reused (delete the folder to rerun). Run from the repository root after building and after
# `cgsr run --config configs/quickstart.yaml` (which writes the parent and the data).
#
#   bash bench/search_strategies.sh [--seeds "1 2"] [--out runs/search-strategies] [--build build]
set -euo pipefail

seeds="1 2"
out=runs/search-strategies
build=build
config=configs/search/compare.yaml
while [ $# -gt 0 ]; do
  case "$1" in
    --seeds) seeds="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    --config) config="$2"; shift 2 ;;
    *) echo "usage: bench/search_strategies.sh [--seeds \"1 2\"] [--out DIR] [--build DIR] [--config FILE]" >&2; exit 2 ;;
  esac
done
cgsr="$build/cgsr"
[ -x "$cgsr" ] || { echo "search_strategies.sh: $cgsr not built (cmake --build $build)" >&2; exit 2; }

for seed in $seeds; do
  for strategy in evolution random; do
    dir="$out/$strategy-seed$seed"
    if [ -f "$dir/results.json" ]; then
      echo "search_strategies.sh: $dir done, reused" >&2
      continue
    fi
    resume=()
    [ -f "$dir/history.jsonl" ] && resume=(--resume)
    echo "search_strategies.sh: $strategy, seed $seed -> $dir" >&2
    "$cgsr" search --config "$config" --strategy "$strategy" --set "seed=$seed" "${resume[@]}" --out "$dir" >&2
  done
done

/usr/bin/python3 - "$out" $seeds <<'PY'
import json, sys
out, seeds = sys.argv[1], sys.argv[2:]
print("| Strategy | Seed | Candidates | Parent (k params, dB) | Pick within tolerance (k params, % of parent, dB) | Pareto front (k params @ dB) |")
print("|---|---:|---:|---|---|---|")
means = {}
for strategy in ("evolution", "random"):
    for seed in seeds:
        r = json.load(open(f"{out}/{strategy}-seed{seed}/results.json"))
        parent, pick = r["parent"]["score"], r["pick"]["score"]
        share = pick["params"] / parent["params"]
        means.setdefault(strategy, []).append(share)
        front = ", ".join(f"{p['params'] / 1000:.1f} @ {p['val_psnr']:.2f}" for p in r["pareto_front"])
        what = "the parent" if r["pick"]["is_parent"] else f"{pick['params'] / 1000:.1f}, {100 * share:.0f}%, {pick['val_psnr']:.3f}"
        print(f"| {strategy} | {seed} | {r['candidates']} | {parent['params'] / 1000:.1f}, {parent['val_psnr']:.3f} | {what} | {front} |")
print()
for strategy, shares in means.items():
    print(f"{strategy}: the pick keeps {100 * sum(shares) / len(shares):.0f}% of the parent's parameters "
          f"(mean of {len(shares)} seed(s); per seed: {', '.join(f'{100 * s:.0f}%' for s in shares)})")
PY
