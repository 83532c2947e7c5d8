#!/usr/bin/env bash
# A profile-guided release build of rt-view: the same source and the same
# results bit for bit, laid out by the compiler for the branches and calls a
# training run actually took (LLVM's profile-guided optimisation).
#
#   scripts/build_pgo.sh [DIR]
#
# Builds an instrumented rt-view, renders every scene in scenes/ small, the
# Cornell box at 64 spp and a 100 k-triangle terrain at 16 spp, runs
# `rt-view bench --quick` (builds, single, packet and bounce rays), merges the
# counts and builds rt-view again with them. DIR (default target/pgo) holds
# the two builds, the counts and the result, DIR/rt-view. Two release builds:
# about 7½ minutes on a 2-core machine. Needs `llvm-profdata` of the
# toolchain's own LLVM, from rustup's `llvm-tools` component (added here
# when rustup is there and it is missing), and python3 (standard library) for
# bench/common/flat_scene.py. docs/performance.md has what it
# buys; `scripts/ab_speed.sh target/release/rt-view DIR/rt-view` measures it.
# RUSTFLAGS already set (say, -Ctarget-cpu=native) go into both builds.
set -euo pipefail
cd "$(dirname "$0")/.."
dir=$(realpath -m "${1:-target/pgo}")
if [[ $dir =~ [[:space:]] ]]; then
  # RUSTFLAGS is split at whitespace: the compiler would get half a path.
  echo "build_pgo.sh: the folder's path has a space in it ($dir); give one without" >&2
  exit 2
fi
sysroot=$(rustc --print sysroot)
host=$(rustc -vV | sed -n 's/^host: //p')
profdata="$sysroot/lib/rustlib/$host/bin/llvm-profdata"
if [[ ! -x $profdata ]] && command -v rustup > /dev/null; then
  echo "== adding rustup's llvm-tools component (for llvm-profdata)"
  rustup component add llvm-tools || true
fi
if [[ ! -x $profdata ]]; then
  echo "build_pgo.sh: no llvm-profdata at $profdata; install it with \`rustup component add llvm-tools\`" >&2
  exit 1
fi
rm -rf "$dir/counts" "$dir/train"
mkdir -p "$dir/counts" "$dir/train"

echo "== instrumented build ($dir/generate)"
RUSTFLAGS="${RUSTFLAGS:-} -Cprofile-generate=$dir/counts" \
  cargo build --release --locked -p rt-view --target-dir "$dir/generate"
trainee="$dir/generate/release/rt-view"

echo "== training runs"
run() {
  if ! "$trainee" "$@" > "$dir/train/log" 2>&1; then
    cat "$dir/train/log" >&2
    echo "build_pgo.sh: training run failed: rt-view $*" >&2
    exit 1
  fi
}
for scene in scenes/*.ron; do
  run render "$scene" --width 96 --height 72 --spp 8 -o "$dir/train/scene.png"
done
run render scenes/cornell_box.ron --width 128 --height 128 --spp 64 -o "$dir/train/cornell.png"
run bench --quick --runs 1 --threads 1 --out "$dir/train" --showcase scenes/showcase.ron
# The terrain the bench wrote, flat-coloured at 640×480 from the bench's
# camera, as bench/mitsuba_flat.py renders it: a pixel's samples traced as
# packets.
flat=$(python3 bench/common/flat_scene.py "$dir/train" 100k)
run render "$flat" --spp 16 -o "$dir/train/flat.png"

echo "== merging the counts"
"$profdata" merge -o "$dir/counts.profdata" "$dir/counts"
# Named by its contents: cargo rebuilds when its flags change, not when a
# file they name does, so new counts under the old name would leave the
# last build in place.
profile="$dir/rt-view-$(sha256sum "$dir/counts.profdata" | cut -c1-16).profdata"
rm -f "$dir"/rt-view-*.profdata
mv "$dir/counts.profdata" "$profile"

echo "== optimised build ($dir/use)"
RUSTFLAGS="${RUSTFLAGS:-} -Cprofile-use=$profile" \
  cargo build --release --locked -p rt-view --target-dir "$dir/use"
cp "$dir/use/release/rt-view" "$dir/rt-view"
echo "wrote $dir/rt-view"
