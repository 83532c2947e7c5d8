#!/usr/bin/env bash
# Renders every scene in scenes/ with two rt-view binaries and says whether
# they give the same images, ray counts and `cast` output: the check that a
# change to the renderer's structure changed no result.
#
#   scripts/same_images.sh OLD_RT_VIEW NEW_RT_VIEW [WORK_DIR]
#
# Each scene is rendered at 128x96 with its own samples per pixel capped at
# 32 (--seed 0 and --seed 7; global-illumination scenes, whose every path
# dimension comes from the sampler, also with --sampler sobol at seed 0)
# to linear OpenEXR, which holds the 32-bit
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
  # Runs: "seed" or "seed sampler".
  runs=("0" "7")
  if grep -q 'global_illumination' "$scene"; then
    runs+=("0 sobol")
  fi
  for run in "${runs[@]}"; do
    read -r seed sampler <<< "$run"
    tag=$seed${sampler:+-$sampler}
    for side in old new; do
      bin=$old; [[ $side == new ]] && bin=$new
      "$bin" render "$scene" --width 128 --height 96 --spp "$spp" --seed "$seed" --stats \
        ${sampler:+--sampler "$sampler"} \
        -o "$work/$side/$name-$tag.exr" 2> "$work/$side/$name-$tag.stats"
    done
    if ! cmp -s "$work/old/$name-$tag.exr" "$work/new/$name-$tag.exr"; then
      echo "DIFFERENT image: $name (seed $seed${sampler:+, $sampler}, $spp spp)"; differ=1
    fi
    if ! diff <(counts "$work/old/$name-$tag.stats") <(counts "$work/new/$name-$tag.stats") > /dev/null; then
      echo "DIFFERENT ray counts: $name (seed $seed${sampler:+, $sampler})"
      diff <(counts "$work/old/$name-$tag.stats") <(counts "$work/new/$name-$tag.stats") || true
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
  echo "every scene: same images (2 seeds; GI scenes also Sobol), ray counts and cast output"
fi
exit $differ
