#!/usr/bin/env bash
# The backbone zoo at about equal cost (docs/results/zoo.md). Every backbone is trained the same
# way on the quickstart's data: plain with the quickstart's train schedule, then with its
# CG-enhanced schedule once plain (the control) and once with the RIT (CG-enhanced), 2 seeds
# (configs/ablate/zoo.yaml). Then one evaluation of them all, latency measured side by side, with
# the classic upscalers and the BSP border upsampler and the quickstart's CG-optimized network,
# on the quickstart's test frames (the default room) and on the held-out corridors, both rendered
# with sub-pixel BSP borders, and one report of the two. SRPO is also trained as its paper does
# (configs/train/srpo_shapes.yaml).
# Needs runs/quickstart (the README's first command). A rerun skips what is finished.
#   scripts/zoo.sh [OUT]        (default runs/zoo; the report is OUT/report/index.html)
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-runs/zoo}"
cgsr="${CGSR:-build/cgsr}"  # another binary: CGSR=path
qs=runs/quickstart
for f in "$qs"/{train,control,enhance,search,scratch}/model.cgsr; do
  [ -f "$f" ] || { echo "scripts/zoo.sh: $f is missing: run build/cgsr run --config configs/quickstart.yaml first" >&2; exit 2; }
done

render() {  # SCENE_CONFIG DIR [--set ...]
  [ -f "$2/results.json" ] || "$cgsr" render --config "$1" --set bsp_border.depth=2 "${@:3}" --out "$2"
}
render configs/scenes/default.yaml "$out/room"
render configs/scenes/corridors.yaml "$out/corridors" --set frames=8
[ -f "$out/shapes/results.json" ] || "$cgsr" render --config configs/scenes/shapes.yaml --out "$out/shapes"

models=() names=()
backbone() {  # DIR NAME SPEC [SOURCE]: SPEC trained plain, then its control and its CG-enhanced version
  local dir="$out/$1" name="$2" source="${4:-hr_unshuffle+hr_fuse}"
  [ -f "$dir/train/model.cgsr" ] ||
    "$cgsr" train --config "$qs/train/config.yaml" --model "$3" --set "name=$name" --out "$dir/train"
  [ -f "$dir/ablate/results.json" ] ||
    "$cgsr" ablate --config configs/ablate/zoo.yaml --set "model=$dir/train/model.cgsr" --set "ablation.sources=[$source]" --out "$dir/ablate"
  models+=("$dir/ablate/variants/plain_control/seed1/model.cgsr" "$dir/ablate/variants/${source//+/_}/seed1/model.cgsr")
  names+=("$name" "CG-enhanced $name")
}
backbone srpo "SRPO x2" srpo
# SRPO also as its paper trains it: on random shapes, with the SSIM loss.
[ -f "$out/srpo_shapes/model.cgsr" ] ||
  "$cgsr" train --config configs/train/srpo_shapes.yaml --set "data=$out/shapes" --out "$out/srpo_shapes"
models+=("$out/srpo_shapes/model.cgsr") names+=("SRPO x2 (shapes, SSIM)")
backbone srcnn "SRCNN-32 x2" configs/models/srcnn_x2_32.yaml
backbone edsr "EDSR-24x4 x2" configs/models/edsr_x2_24.yaml
backbone pan24 "PAN-24x10 x2" configs/models/pan_x2_24.yaml
backbone span28 "SPAN-28 x2" configs/models/span_x2_28.yaml hr_unshuffle  # no HR features to fuse into
# PAN x2 at full size and the CG-optimized one: the quickstart's own networks (one seed).
models+=("$qs/control/model.cgsr" "$qs/enhance/model.cgsr" "$qs/search/model.cgsr" "$qs/scratch/model.cgsr")
names+=("PAN x2" "CG-enhanced PAN x2" "CG-optimized PAN x2" "CG-optimized PAN x2 (scratch)")

evaluate() {  # DATA SPLIT DIR
  local config="$out/eval_$(basename "$3").yaml"
  {
    echo "data: $1"
    printf 'models: [classic'; printf ', "%s"' "${models[@]}"; echo ']'
    printf 'names: [""'; printf ', "%s"' "${names[@]}"; echo ']'
    echo "eval: {split: $2, latency_runs: 7}"
  } > "$config"
  "$cgsr" eval --config "$config" --out "$3"
}
evaluate "$out/room" test "$out/eval_room"
evaluate "$out/corridors" all "$out/eval_corridors"
"$cgsr" report "$out/eval_room" "$out/eval_corridors" --out "$out/report"
