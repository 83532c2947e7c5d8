#!/usr/bin/env bash
# Mutation testing of rt-core's numeric core with cargo-mutants: each mutant
# (an operator swapped, a constant changed, a function body replaced) is
# built and rt-core's unit tests are run against it; a mutant no test fails
# on is "missed". Results: docs/testing.md, "Mutation testing".
#
#   cargo install cargo-mutants --locked
#   scripts/mutants.sh crates/rt-core/src/geometry/sphere.rs [more files...]
#
# MUTANTS_SHARD=K/N runs every N-th mutant from the K-th (0-based; cargo
# mutants --shard K/N --sharding round-robin): a sample spread over the
# whole file, for files too large to run whole in one sitting.
#
# MUTANTS_ITERATE=1 tests again only the mutants a previous run of the same
# file missed or timed out on (cargo mutants --iterate), after new tests.
#
# Outcomes go to target/mutants/<file stem>/mutants.out (caught.txt,
# missed.txt, unviable.txt, timeout.txt). Runs in place (the source is
# restored after each mutant), so leave the tree alone while it runs.
#
# Speed on 2 cores: rt-core is built at opt-level 0 (an incremental build
# of one mutant takes 2-6 s instead of 10 s), and the handful of tests that
# take seconds at opt-level 0 are left out where they cannot reach the file
# (the BSDF quadratures, glTF corruption, the subsurface walks, the 15 s
# fine-grid mesh test for files other than triangle.rs and mesh.rs).
set -euo pipefail
cd "$(dirname "$0")/.."
# MUTANTS_OPT_LEVEL=1 builds at the dev profile's own level instead: 10 s a
# mutant, but the BSDF, emitter and path-tracing tests then take seconds,
# not tens of seconds (the better choice for those files).
export CARGO_PROFILE_DEV_OPT_LEVEL="${MUTANTS_OPT_LEVEL:-0}" CARGO_PROFILE_DEV_DEBUG=false
slow_elsewhere='test(/^(gltf_model|mtl|obj_model)::/)'
for file in "$@"; do
  stem=$(basename "$file" .rs)
  case "$stem" in
    bsdf|sampler|medium|emitter|light|light_sampler|path_tracer|tracer|shading|material)
      filter="not ($slow_elsewhere | test(/a_fine_grid_far_away/))" ;;
    triangle|mesh)
      filter="not ($slow_elsewhere | test(/^(bsdf|medium|path_tracer)::/))" ;;
    *)
      filter="not ($slow_elsewhere | test(/^(bsdf|medium|path_tracer)::/) | test(/a_fine_grid_far_away/))" ;;
  esac
  echo "== $file (tests: $filter)"
  mkdir -p "target/mutants/$stem"
  # Exit status 2 (some missed) and 3 (some timed out) are results, not failures.
  status=0
  shard=()
  if [[ -n "${MUTANTS_SHARD:-}" ]]; then shard=(--shard "$MUTANTS_SHARD" --sharding round-robin); fi
  if [[ -n "${MUTANTS_ITERATE:-}" ]]; then shard+=(--iterate); fi
  cargo mutants --in-place -p rt-core -f "$file" "${shard[@]}" -o "target/mutants/$stem" -- --lib -E "$filter" || status=$?
  case $status in 0|2|3) ;; *) exit "$status" ;; esac
done
