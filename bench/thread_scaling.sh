#!/usr/bin/env bash
# Thread scaling: the renders, rays and builds of docs/performance.md
# ("Past two cores") at each thread count, on the machine it runs on.
#
#   bench/thread_scaling.sh [THREADS [ROUNDS [OUT]]]      # THREADS e.g. 1,2,4,8,12,16
#
# RT_VIEW names the binary (default target/release/rt-view; build it with
# `cargo build --release -p rt-view`). It runs
#   - `rt-view bench --runs 7 --threads THREADS` twice (OUT/bench_a.csv, bench_b.csv),
#   - `bench/embree_primary.py` on the same rays where Python has embreex and numpy,
#   - the builds alone: `rt-view bench --build-only --runs 7 --threads THREADS`, each
#     build's steps with it (items, binary tree, leaf list, collapse, finish), and
#     Embree's commits alone (`bench/embree_primary.py --build-only`) where it can,
#   - ROUNDS rounds (default 5), the thread counts taking turns, of the Cornell box
#     (384x384, 64 spp, path tracing) and of the 1 M terrain's flat 64-spp render
#     (bench/common/flat_scene.py, as bench/mitsuba_flat.py renders it), each line its
#     `tracing` time from --stats,
# and prints the medians, speed-ups over the first thread count and the run-to-run spread
# ((slowest - fastest) / median) of the renders. Everything lands in OUT
# (default thread-scaling-out).
set -euo pipefail
cd "$(dirname "$0")/.."
threads=${1:-1,2,4,8,12,16}
rounds=${2:-5}
out=${3:-thread-scaling-out}
rt=${RT_VIEW:-target/release/rt-view}
mkdir -p "$out"
for pass in a b; do
  "$rt" bench --runs 7 --threads "$threads" --out "$out" > "$out/bench_$pass.log" 2>&1
  cp "$out/bench.csv" "$out/bench_$pass.csv"
  grep -E '^ +(mesh|10k|100k|1m) ' "$out/bench_$pass.log"
done
# Whether python3 can run Embree (embreex and numpy), asked once.
if python3 -c 'import embreex, numpy' 2>/dev/null; then embree=1; else embree=0; fi
if [[ $embree == 1 ]]; then
  python3 bench/embree_primary.py "$out" --runs 7 --threads "$threads" | tee "$out/embree.log"
else
  echo "(no embreex/numpy for python3: Embree left out)"
fi
"$rt" bench --build-only --runs 7 --threads "$threads" --out "$out" 2>&1 | grep -v generating | tee "$out/builds.log"
if [[ $embree == 1 ]]; then
  python3 bench/embree_primary.py "$out" --build-only --runs 7 --threads "$threads" | tee "$out/embree_builds.log"
fi
flat=$(python3 bench/common/flat_scene.py "$out" 1m)
: > "$out/renders.log"
for r in $(seq "$rounds"); do
  for t in ${threads//,/ }; do
    for scene in cornell flat; do
      if [ $scene = cornell ]; then
        args=(scenes/cornell_box.ron --width 384 --height 384 --spp 64)
      else
        args=("$flat" --spp 64)
      fi
      line=$(RAYON_NUM_THREADS=$t "$rt" render "${args[@]}" -o "$out/$scene.exr" --stats 2>&1 | grep '^tracing')
      echo "$scene $t $line" | tee -a "$out/renders.log"
    done
  done
done
python3 - "$out/renders.log" <<'PY'
import collections, statistics, sys
times = collections.defaultdict(list)
for line in open(sys.argv[1]):
    scene, t, _, seconds = line.split()[:4]
    times[(scene, int(t))].append(float(seconds))
for scene in ("cornell", "flat"):
    counts = sorted(t for s, t in times if s == scene)
    base = statistics.median(times[(scene, counts[0])])
    for t in counts:
        x = times[(scene, t)]
        m = statistics.median(x)
        print(f"{scene:8} {t:3} threads: median {m:.3f} s, {base / m:5.2f}x the speed on {counts[0]}, "
              f"spread {(max(x) - min(x)) / m * 100:3.0f} % over {len(x)} rounds")
PY
