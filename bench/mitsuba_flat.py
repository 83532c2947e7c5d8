#!/usr/bin/env python3
"""Coherent rays against Mitsuba 3: the 1 M-triangle terrain, flat-coloured.

    pip install mitsuba numpy
    cargo build --release -p rt-view
    target/release/rt-view bench --out bench-out      # writes the terrain meshes and camera
    python3 bench/mitsuba_flat.py bench-out --threads 2 [--mesh 1m] [--spp 1,4,16,64] [--llvm-lanes 8]

Both renderers draw the terrain from the bench camera at 640×480 with N
samples per pixel, every sample one camera ray and nothing else:
`rt-view render --spp N` on a scene without lights (a hit shows its
material's colour), and Mitsuba's `llvm_ad_rgb` variant with the `aov`
integrator returning the albedo of the surface hit (one ray per sample;
Mitsuba traces the whole wavefront of rays through Embree). The time of
rt-view is its `tracing` time from `--stats` (scene loading and the BVH build
left out); Mitsuba's is `mi.render` until the image is evaluated, with its
first render at each sample count (which compiles the kernels) untimed; both
medians of `--runs`, on `--threads` threads. It prints samples per second
and rt-view's over Mitsuba's, and the fraction of pixels each finds covered
by the terrain (they should agree).

Dr.Jit compiles Mitsuba's kernels for the host CPU at its widest vectors
(16 lanes with AVX-512, whose rays then reach Embree 16 at a time);
`--llvm-lanes 8` makes them 8 wide, as AVX2 has them (rt-view's node and
leaf tests are 8 wide), to see what the wider vectors bring.

Mitsuba's world is right-handed and ours left-handed: the mesh is mirrored
in x, and so is the camera, whose up stays.
"""

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mitsuba_compare  # noqa: E402  (LLVM selection)
from common.flat_scene import COLOR, HEIGHT, WIDTH, rt_scene  # noqa: E402


def rt_view_render(binary, scene, spp, threads, out):
    """rt-view's tracing time in seconds and its image (linear, from EXR)."""
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    res = subprocess.run([binary, "render", scene, "--spp", str(spp), "--stats", "-o", out],
                         env=env, capture_output=True, text=True, check=True)
    m = re.search(r"tracing: ([0-9.]+) s", res.stderr)
    if not m:
        raise SystemExit("no tracing time in rt-view's --stats output:\n" + res.stderr)
    return float(m.group(1))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="the folder `rt-view bench --out` wrote")
    ap.add_argument("--mesh", default="1m", help="which terrain (10k, 100k, 1m)")
    ap.add_argument("--spp", default="1,4,16,64")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--threads", type=int, default=os.cpu_count())
    ap.add_argument("--rt-view", default="target/release/rt-view")
    ap.add_argument("--llvm-lanes", type=int, help="Mitsuba's kernels this many lanes wide (8), not the CPU's widest")
    args = ap.parse_args()
    counts = [int(n) for n in args.spp.split(",")]

    mesh = os.path.join(args.out, f"terrain_{args.mesh}.obj")
    cam = json.load(open(mesh[:-4] + ".json"))
    scene_file = rt_scene(args.out, mesh, cam)
    exr = os.path.join(args.out, "flat_rt_view.exr")

    mitsuba_compare.use_llvm19()
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(args.threads)
    if args.llvm_lanes:
        mitsuba_compare.set_llvm_lanes(dr, mi, args.llvm_lanes)
    mirror = lambda p: [-p[0], p[1], p[2]]  # noqa: E731
    T = mi.ScalarTransform4f
    scene = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "aov", "aovs": "albedo:albedo"},
        "sensor": {
            "type": "perspective",
            "fov": cam["fov_y"], "fov_axis": "y",
            "to_world": T().look_at(origin=mirror(cam["position"]), target=mirror(cam["center_of_interest"]),
                                    up=cam["up"]),
            "film": {"type": "hdrfilm", "width": WIDTH, "height": HEIGHT, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent"},
        },
        "terrain": {
            "type": "obj", "filename": mesh, "face_normals": True,
            "to_world": T().scale([-1, 1, 1]),
            "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(COLOR)}},
        },
    })

    def mitsuba_render(spp):
        t0 = time.perf_counter()
        img = mi.render(scene, spp=spp)
        dr.eval(img)
        arr = np.array(img)
        return time.perf_counter() - t0, arr

    lanes = mitsuba_compare.llvm_lanes(dr)
    print(f"terrain {args.mesh}, {WIDTH}x{HEIGHT}, {args.threads} threads, medians of {args.runs} runs; "
          f"Mitsuba's kernels {lanes} lanes wide")
    print(f"{'spp':>5} {'rt-view s':>10} {'Mitsuba s':>10} {'rt-view Msamples/s':>19} {'Mitsuba Msamples/s':>19} "
          f"{'ratio':>7} {'covered rt-view':>16} {'covered Mitsuba':>16}")
    for spp in counts:
        mitsuba_render(spp)  # compiles the kernels for this count
        ours, theirs = [], []
        for _ in range(args.runs):
            ours.append(rt_view_render(args.rt_view, scene_file, spp, args.threads, exr))
            t, arr = mitsuba_render(spp)
            theirs.append(t)
        a, b = statistics.median(ours), statistics.median(theirs)
        samples = WIDTH * HEIGHT * spp / 1e6
        ours_img = mitsuba_compare.read_exr(mi, exr)
        # The aov integrator's image holds the albedo alone (0 where nothing is hit).
        covered_ours = float((ours_img.sum(axis=2) > 0).mean())
        covered_theirs = float((arr[:, :, :3].sum(axis=2) > 0).mean())
        print(f"{spp:>5} {a:>10.4f} {b:>10.4f} {samples / a:>19.2f} {samples / b:>19.2f} {b / a:>6.2f}x "
              f"{covered_ours:>16.4f} {covered_theirs:>16.4f}", flush=True)


if __name__ == "__main__":
    main()
