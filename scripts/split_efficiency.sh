#!/usr/bin/env bash
# What splitting a render into N parts costs: renders SCENE once
# (`rt-view render`), then for each N its N parts one after the other, each
# with the whole machine as a cluster task has its node, and merges them.
#
#   scripts/split_efficiency.sh [--cache] RT_VIEW SCENE "1 2 4 8 16 64" [render options...]
#
# With --cache the tasks read a scene cache (`rt-view prepare`, made once
# before them; its CPU seconds go to stderr, not into the tasks' total)
# instead of the scene file; the one render still reads the scene file.
#
# Prints CSV on stdout: N, the tasks' total CPU seconds (user + system, from
# /usr/bin/time) and wall seconds, what the tasks say they spent loading
# (scene parse, BVH build, content hash), rendering and writing, the
# merge's wall seconds, and the efficiency: the one render's CPU seconds
# over the N tasks' (1 = no cost to splitting). The first row, N = 0, is the
# one render. Every merged image is checked against the one render, byte
# for byte.
set -euo pipefail
cache=0
if [[ ${1:-} == --cache ]]; then
  cache=1
  shift
fi
if [[ $# -lt 3 ]]; then
  sed -n '2,19p' "$0"
  exit 2
fi
rt_view=$(realpath "$1")
scene=$2
counts=$3
shift 3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Runs rt-view with "$@", appending "wall cpu" to $work/time and its stderr to $work/err.
timed() {
  /usr/bin/time -f "%e %U %S" -o "$work/t" "$rt_view" "$@" 2>>"$work/err"
  awk '{ printf "%s %.3f\n", $1, $2 + $3 }' "$work/t" >>"$work/time"
}
# Sums of the "load X s, render Y s, write Z s" lines of $work/err.
phases() {
  grep -o -E 'load [0-9.]+ s, render [0-9.]+ s, write [0-9.]+ s' "$work/err" |
    awk '{ l += $2; r += $5; w += $8 } END { printf "%.3f,%.3f,%.3f", l, r, w }'
}

echo "parts,cpu_s,wall_s,load_s,render_s,write_s,merge_wall_s,efficiency"
: >"$work/time"
: >"$work/err"
timed render "$scene" -o "$work/whole.exr" "$@"
read -r one_wall one_cpu <"$work/time"
echo "0,$one_cpu,$one_wall,,,,,1.000"
task_scene=$scene
if ((cache)); then
  /usr/bin/time -f "%e %U %S" -o "$work/t" "$rt_view" prepare "$scene" -o "$work/scene.rtc" 2>>"$work/err"
  awk '{ printf "prepare: %s wall s, %.3f CPU s\n", $1, $2 + $3 }' "$work/t" >&2
  task_scene=$work/scene.rtc
fi
for n in $counts; do
  : >"$work/time"
  : >"$work/err"
  parts=()
  for ((k = 0; k < n; k++)); do
    timed render "$task_scene" --part "$k/$n" -o "$work/part-$k.rtpart" "$@"
    parts+=("$work/part-$k.rtpart")
  done
  read -r wall cpu < <(awk '{ w += $1; c += $2 } END { printf "%.3f %.3f\n", w, c }' "$work/time")
  merge_start=$(date +%s.%N)
  "$rt_view" merge "${parts[@]}" -o "$work/merged.exr" 2>/dev/null
  merge=$(echo "$(date +%s.%N) - $merge_start" | bc)
  cmp -s "$work/merged.exr" "$work/whole.exr" || { echo "N=$n: the merged image differs" >&2; exit 1; }
  printf '%s,%s,%s,%s,%.3f,%.3f\n' "$n" "$cpu" "$wall" "$(phases)" "$merge" "$(echo "$one_cpu / $cpu" | bc -l)"
  rm -f "${parts[@]}"
done
