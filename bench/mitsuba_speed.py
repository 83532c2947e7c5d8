#!/usr/bin/env python3
"""How long rt-view and Mitsuba 3 take to reach the same noise on a scene.

    pip install mitsuba numpy
    cargo build --release -p rt-view
    python3 bench/mitsuba_speed.py scenes/cornell_box.ron --threads 2

The scene is converted as `bench/mitsuba_compare.py` converts it. A reference
is rendered by Mitsuba's `llvm_ad_rgb` variant with `--reference-spp`
samples. Then rt-view, Mitsuba `scalar_rgb` and Mitsuba `llvm_ad_rgb` each
render the scene at every count of `--spp`, `--runs` times (the median time
counts; Mitsuba's first render of a variant, which compiles its kernels, is
not timed), on the same number of threads. The RMSE of each image against
the reference (linear radiance, all pixels and channels) falls as 1/√spp
for an unbiased renderer, so the time each needs to reach a target RMSE is
`time(n)·(rmse(n)/target)²`; the target is Mitsuba `llvm_ad_rgb`'s RMSE at
the largest count. `--llvm-lanes 8` makes `llvm_ad_rgb`'s kernels 8
lanes wide instead of the CPU's widest (16 with AVX-512), reference
included (`bench/mitsuba_flat.py` says more).
"""

import argparse
import os
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mitsuba_compare  # noqa: E402  (the scene conversion)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene")
    p.add_argument("--spp", default="16,64", help="sample counts to time, comma-separated")
    p.add_argument("--reference-spp", type=int, default=4096)
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--threads", type=int, default=os.cpu_count())
    p.add_argument("--rt-view", default="target/release/rt-view")
    p.add_argument("--out", default="mitsuba-out")
    p.add_argument("--llvm-lanes", type=int, help="llvm_ad_rgb's kernels this many lanes wide (8), not the CPU's widest")
    args = p.parse_args()
    counts = [int(n) for n in args.spp.split(",")]

    import drjit as dr
    import mitsuba as mi

    mitsuba_compare.use_llvm19()
    name = os.path.splitext(os.path.basename(args.scene))[0]
    folder = os.path.join(args.out, name + "-speed")
    desc = mitsuba_compare.export_scene(args.rt_view, args.scene, folder)
    w, h = desc["width"], desc["height"]

    scenes = {}

    def mitsuba(variant):
        if variant not in scenes:
            mi.set_variant(variant)
            dr.set_thread_count(args.threads)
            if args.llvm_lanes and variant.startswith("llvm"):
                mitsuba_compare.set_llvm_lanes(dr, mi, args.llvm_lanes)
            scenes[variant] = mi.load_dict(mitsuba_compare.mitsuba_scene(mi, desc, folder, w, h, 400.0))
        mi.set_variant(variant)
        return scenes[variant]

    def render_mitsuba(variant, spp, seed):
        scene = mitsuba(variant)
        start = time.perf_counter()
        image = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)[:, :, :3]
        return image, time.perf_counter() - start

    def render_rt(spp, seed):
        out = os.path.join(folder, "rt.exr")
        env = dict(os.environ, RAYON_NUM_THREADS=str(args.threads))
        command = [args.rt_view, "render", args.scene, "-o", out, "--spp", str(spp), "--seed", str(seed)]
        start = time.perf_counter()
        subprocess.run(command, check=True, env=env, stderr=subprocess.DEVNULL)
        elapsed = time.perf_counter() - start
        mi.set_variant("scalar_rgb")
        return mitsuba_compare.read_exr(mi, out), elapsed

    print(f"reference: Mitsuba llvm_ad_rgb, {args.reference_spp} spp ...", flush=True)
    reference, _ = render_mitsuba("llvm_ad_rgb", args.reference_spp, 1000)
    print(f"Mitsuba llvm_ad_rgb's kernels are {mitsuba_compare.llvm_lanes(dr)} lanes wide", flush=True)
    render_mitsuba("scalar_rgb", 1, 999)  # load and warm up
    renderers = {
        "rt-view": render_rt,
        "Mitsuba scalar_rgb": lambda spp, seed: render_mitsuba("scalar_rgb", spp, seed),
        "Mitsuba llvm_ad_rgb": lambda spp, seed: render_mitsuba("llvm_ad_rgb", spp, seed),
    }
    results = {}
    for label, render in renderers.items():
        for spp in counts:
            times, errors = [], []
            for run in range(args.runs):
                image, elapsed = render(spp, run + 1)
                times.append(elapsed)
                errors.append(float(np.sqrt(np.mean((image - reference) ** 2))))
            results[(label, spp)] = (float(np.median(times)), float(np.mean(errors)))
            print(f"{label} {spp} spp: {results[(label, spp)][0]:.3f} s, RMSE {results[(label, spp)][1]:.5f}", flush=True)

    top = max(counts)
    target = results[("Mitsuba llvm_ad_rgb", top)][1]
    lines = [
        f"# {name}: time to the same noise, {w}×{h}, {args.threads} threads",
        "",
        f"Target RMSE {target:.5f} (Mitsuba llvm_ad_rgb at {top} spp, against a {args.reference_spp}-spp reference).",
        "",
        "| renderer | spp | time (s) | RMSE | time to the target RMSE (s) |",
        "|---|---:|---:|---:|---:|",
    ]
    to_target = {}
    for (label, spp), (t, e) in results.items():
        needed = t * (e / target) ** 2
        if spp == top:
            to_target[label] = needed
        lines.append(f"| {label} | {spp} | {t:.3f} | {e:.5f} | {needed:.2f} |")
    lines.append("")
    for label in ("Mitsuba scalar_rgb", "Mitsuba llvm_ad_rgb"):
        lines.append(f"- rt-view / {label}: {to_target[label] / to_target['rt-view']:.2f}× as fast")
    report = "\n".join(lines) + "\n"
    print(report)
    with open(os.path.join(folder, "speed.md"), "w") as f:
        f.write(report)


if __name__ == "__main__":
    main()
