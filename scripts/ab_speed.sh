#!/usr/bin/env bash
# A/B speed of two rt-view builds on the same machine in one run: renders of
# a few scenes, old and new alternating (the order swapped every run, so a
# drift of the machine's speed hits both alike), and each build's `bench`.
#
#   scripts/ab_speed.sh OLD_RT_VIEW NEW_RT_VIEW [RUNS] [THREADS]
#
# RUNS timed renders of each scene per build (default 7); THREADS the thread
# counts `bench` measures (default "1,2"). Prints, per scene, the median
# tracing time of each build (from `--stats`) and new/old; then each build's
# bench table (medians of 3 runs each). Release builds only: debug timings
# say nothing. AB_CASES="scene w h spp;scene w h spp" replaces the scenes;
# AB_BENCH=0 skips the bench; RAYON_NUM_THREADS sets the renders' threads.
set -euo pipefail
if [[ $# -lt 2 ]]; then
  sed -n '2,12p' "$0"
  exit 2
fi
old=$(realpath "$1")
new=$(realpath "$2")
runs=${3:-7}
threads=${4:-1,2}
cd "$(dirname "$0")/.."
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# scene, width, height, spp: a path-traced room, the flat-shaded showcase,
# the subsurface scene, a mesh scene.
cases=(
  "scenes/cornell_box.ron 320 240 64"
  "scenes/showcase.ron 640 480 4"
  "scenes/subsurface.ron 160 120 32"
  "scenes/mesh.ron 640 480 4"
)
if [[ -n "${AB_CASES:-}" ]]; then IFS=';' read -r -a cases <<< "$AB_CASES"; fi
median() { sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR + 1) / 2] : (a[NR / 2] + a[NR / 2 + 1]) / 2}'; }
tracing() { sed -n 's/^tracing: \([0-9.]*\) s.*/\1/p' "$1"; }
echo "A/B render times ($runs runs each, alternating; median tracing seconds)"
printf '%-28s %10s %10s %8s\n' scene old new new/old
for case in "${cases[@]}"; do
  read -r scene w h spp <<< "$case"
  name=$(basename "$scene" .ron)
  : > "$work/old.$name"
  : > "$work/new.$name"
  for ((r = 0; r < runs; r++)); do
    order=(old new)
    ((r % 2)) && order=(new old)
    for side in "${order[@]}"; do
      bin=$old; [[ $side == new ]] && bin=$new
      "$bin" render "$scene" --width "$w" --height "$h" --spp "$spp" --stats -o "$work/$side.exr" 2> "$work/stats"
      tracing "$work/stats" >> "$work/$side.$name"
    done
  done
  a=$(median < "$work/old.$name")
  b=$(median < "$work/new.$name")
  printf '%-28s %10.4f %10.4f %8.3f\n' "$name ${w}x$h ${spp}spp" "$a" "$b" "$(awk -v a="$a" -v b="$b" 'BEGIN {print b / a}')"
done
[[ "${AB_BENCH:-1}" == 0 ]] && exit 0
for side in old new; do
  bin=$old; [[ $side == new ]] && bin=$new
  echo
  echo "bench, $side build:"
  "$bin" bench --quick --runs 3 --threads "$threads" --out "$work/bench-$side" 2>/dev/null
done
