#!/usr/bin/env python3
"""How much clean image two or more rt-view builds give per second of
tracing, on the same scenes: the efficiency of a sampling change.

    pip install mitsuba numpy        # mitsuba only reads the EXR files
    python3 bench/render_efficiency.py --rt-view OLD,NEW scenes/caustic.ron scenes/cornell_box.ron

Each scene is rendered `--seeds` times by every build (`rt-view render SCENE
--width W --height H --spp N --sampler S --seed s --stats`, s = 1, 2, …, the
builds taking turns seed by seed so that drift on a shared machine falls on
all alike), on `--threads` threads (one by default: no scheduling noise).
For each build:

- time: the median of its `tracing` times (loading and the BVH build left
  out);
- variance: the per-pixel variance over the seeds' images (every channel),
  averaged over the image, of radiance clamped to [0, 1] (as a display and
  `bench/time_to_clean.py` count it: a lamp of radiance 17 would otherwise
  outweigh the room) and unclamped;
- efficiency: 1/(variance × time), printed relative to the first build: how
  many times less time it needs for the same noise;
- the image mean over all seeds, which an unbiased change leaves the same up
  to noise.
"""

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mitsuba_compare  # noqa: E402  (its EXR reader)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scenes", nargs="+", help="rt-view scene files (.ron)")
    p.add_argument("--rt-view", default="target/release/rt-view",
                   help="the builds, comma-separated; the first is the baseline")
    p.add_argument("--seeds", type=int, default=12, help="renders per build and scene")
    p.add_argument("--spp", type=int, default=64)
    p.add_argument("--size", default="96x96", help="WIDTHxHEIGHT")
    p.add_argument("--sampler", default="sobol", help="stratified or sobol")
    p.add_argument("--threads", type=int, default=1)
    args = p.parse_args()
    if args.seeds < 2:
        p.error("--seeds must be at least 2 (a variance needs two images)")
    builds = args.rt_view.split(",")
    width, height = args.size.split("x")

    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    env = dict(os.environ, RAYON_NUM_THREADS=str(args.threads))
    print(f"{args.size}, {args.spp} spp, {args.sampler}, {args.seeds} seeds, {args.threads} thread(s); "
          f"efficiency relative to {builds[0]}")
    print(f"{'scene':<22} {'build':<28} {'time s':>7} {'var clamped':>12} {'var':>12} "
          f"{'eff clamped':>12} {'eff':>7} {'mean':>9}")
    with tempfile.TemporaryDirectory() as tmp:
        for scene in args.scenes:
            images = {b: [] for b in builds}
            times = {b: [] for b in builds}
            for seed in range(1, args.seeds + 1):
                for i, build in enumerate(builds):
                    out = os.path.join(tmp, f"{i}.exr")
                    command = [build, "render", scene, "-o", out, "--width", width, "--height", height,
                               "--spp", str(args.spp), "--sampler", args.sampler, "--seed", str(seed), "--stats"]
                    done = subprocess.run(command, env=env, capture_output=True, text=True)
                    if done.returncode != 0:
                        raise SystemExit(f"{build} failed on {scene}: {done.stderr.strip()[-300:]}")
                    tracing = re.search(r"tracing: ([0-9.]+) s", done.stderr)
                    if not tracing:
                        raise SystemExit(f"no tracing time in {build}'s --stats output:\n{done.stderr}")
                    times[build].append(float(tracing.group(1)))
                    images[build].append(mitsuba_compare.read_exr(mi, out))
            baseline = None
            for build in builds:
                stack = np.stack(images[build])
                clamped = np.clip(stack, 0.0, 1.0).var(axis=0, ddof=1).mean()
                plain = stack.var(axis=0, ddof=1).mean()
                t = statistics.median(times[build])
                eff = (1.0 / (clamped * t), 1.0 / (plain * t))
                baseline = baseline or eff
                print(f"{os.path.basename(scene):<22} {build[-28:]:<28} {t:>7.3f} {clamped:>12.4e} {plain:>12.4e} "
                      f"{eff[0] / baseline[0]:>11.2f}x {eff[1] / baseline[1]:>6.2f}x {stack.mean():>9.5f}", flush=True)


if __name__ == "__main__":
    main()
