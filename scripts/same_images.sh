#!/usr/bin/env bash
# Renders every scene in scenes/ with two rt-view binaries and says whether
# they give the same images, ray counts and `cast` output: the check that a
# change to the renderer's structure changed no result.
#
#   scripts/same_images.sh OLD_RT_VIEW NEW_RT_VIEW [WORK_DIR]
#
# Each scene is rendered at 128x96 with its own samples per pixel capped at
# 32 (--seed 0 and --seed 7) to linear OpenEXR, which holds the 32-bit
# floats exactly, and the files are compared byte for byte; the ray-count
# lines of --stats are compared as text (the timing lines are not); and
# `cast --pixels` at 32x24 is compared as text. Exit status 1 when anything
# differs, with each difference named; the images stay in WORK_DIR
# (default: a temporary folder) for a closer look.
set -euo pipefail
if [[ $# -lt 2 ]]; then
  sed -n '2,14p' "$0"
  exit 2
fi
old=$(realpath "$1")
new=$(realpath "$2")
cd "$(dirname "$0")/.."
work=${3:-$(mktemp -d)}
mkdir -p "$work/old" "$work/new"
differ=0
# The ray-count lines of --stats: everything but times and rates.
counts() { grep -v -E 'time|took|Mrays/s| s$| ms$|load|build' "$1" || true; }
for scene in scenes/*.ron; do
  name=$(basename "$scene" .ron)
  spp=$(grep -o -E 'samples_per_pixel: *[0-9]+' "$scene" | grep -o -E '[0-9]+$' || echo 1)
  spp=$(( spp > 32 ? 32 : spp ))
  for seed in 0 7; do
    for side in old new; do
      bin=$old; [[ $side == new ]] && bin=$new
      "$bin" render "$scene" --width 128 --height 96 --spp "$spp" --seed "$seed" --stats \
        -o "$work/$side/$name-$seed.exr" 2> "$work/$side/$name-$seed.stats"
    done
    if ! cmp -s "$work/old/$name-$seed.exr" "$work/new/$name-$seed.exr"; then
      echo "DIFFERENT image: $name (seed $seed, $spp spp)"; differ=1
    fi
    if ! diff <(counts "$work/old/$name-$seed.stats") <(counts "$work/new/$name-$seed.stats") > /dev/null; then
      echo "DIFFERENT ray counts: $name (seed $seed)"
      diff <(counts "$work/old/$name-$seed.stats") <(counts "$work/new/$name-$seed.stats") || true
      differ=1
    fi
  done
  for side in old new; do
    bin=$old; [[ $side == new ]] && bin=$new
    "$bin" cast "$scene" --pixels --width 32 --height 24 > "$work/$side/$name.csv"
  done
  if ! cmp -s "$work/old/$name.csv" "$work/new/$name.csv"; then
    echo "DIFFERENT cast output: $name"; differ=1
  fi
  echo "checked $name ($spp spp)"
done
if [[ $differ == 0 ]]; then
  echo "every scene: same images (2 seeds), ray counts and cast output"
fi
exit $differ
