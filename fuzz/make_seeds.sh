#!/usr/bin/env bash
# Regenerates the seed inputs in fuzz/corpus/ from what cgsr itself writes: the manifest and
# the 64x48 files of frame 0 of configs/scenes/tiny.yaml with decompression bombs beside them
# (and its sub-pixel BSP border file, rendered with bsp_border: {depth: 2})
# (fuzz/make_bomb_seeds.py), and a small CG-enhanced PAN model file (format version 2) next to
# the version 1 test fixture (tests/data/model_file_v1.cgsr, which this cgsr can no longer write).
# Config seeds are the files in configs/ (the fuzz tests read them there) plus the hand-written
# ones in fuzz/corpus/config/ (regressions and the configs' former shapes), which this script
# leaves alone.
#   fuzz/make_seeds.sh [BUILD_DIR]     (default: build)
set -euo pipefail
cd "$(dirname "$0")/.."
cgsr="${1:-build}/cgsr"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

"$cgsr" render --config configs/scenes/tiny.yaml --set frames=3 --out "$work/data" >/dev/null
rm -rf fuzz/corpus/manifest fuzz/corpus/frame_files fuzz/corpus/model_file fuzz/corpus/bsp_border
mkdir -p fuzz/corpus/manifest fuzz/corpus/frame_files fuzz/corpus/model_file fuzz/corpus/bsp_border
cp "$work/data/manifest.yaml" fuzz/corpus/manifest/tiny_manifest.yaml

# fuzz_frame_files reads the file kind from the first byte (FileKind order in dataset_manifest.h).
kind_byte=0
for kind in color depth normal normal_angle edge id motion; do
  file="$(ls "$work/data/64x48/$kind/000000."*)"
  { printf "\\$(printf %03o "$kind_byte")"; cat "$file"; } > "fuzz/corpus/frame_files/$kind.bin"
  kind_byte=$((kind_byte + 1))
done

"$cgsr" render --config configs/scenes/tiny.yaml --set frames=3 --set bsp_border.depth=2 --out "$work/bsp" >/dev/null
cp "$work/bsp/64x48/bsp_border/000000.bsp" fuzz/corpus/bsp_border/tiny_000000.bsp
cp "$work/bsp/manifest.yaml" fuzz/corpus/manifest/tiny_bsp_border_manifest.yaml

# Decompression bombs (PNG, JPEG, EXR), each a few KB declaring 20000x20000 pixels.
python3 fuzz/make_bomb_seeds.py

printf 'backbone: pan\nscale: 2\nblocks: 1\nwidths: {features: 8}\n' > "$work/spec.yaml"
"$cgsr" train --data "$work/data" --model "$work/spec.yaml" --out "$work/train" --threads 1 \
  --set enhance.enabled=true --set enhance.rit.width=4 --set enhance.geometry.enabled=false \
  --set schedule.steps=2 --set schedule.batch_size=1 --set schedule.patch_size=16 \
  --set schedule.validate_every=0 --set schedule.val_frames=1 >/dev/null
cp "$work/train/model.cgsr" fuzz/corpus/model_file/pan_cg_tiny.cgsr
cp tests/data/model_file_v1.cgsr fuzz/corpus/model_file/pan_cg_tiny_v1.cgsr
ls -l fuzz/corpus/*
