#!/usr/bin/env bash
# How fast the error of each sampler (stratified, Sobol) falls with samples
# per pixel, on every global-illumination scene in scenes/: the table of
# docs/sampling.md. Runs crates/rt-core/examples/sampler_convergence.rs
# (which says what is measured); extra arguments go to it, e.g.
#
#   bench/sampler_convergence.sh --width 48 --height 36 --reference-spp 8192 --max-spp 1024
#
# Takes about half an hour on two busy cores at those settings.
set -euo pipefail
cd "$(dirname "$0")/.."
scenes=$(grep -l global_illumination scenes/*.ron)
cargo run -q -p rt-core --example sampler_convergence -- $scenes "$@"
