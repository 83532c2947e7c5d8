#!/usr/bin/env python3
"""Cast the same primary rays as `rt-view bench` with Intel Embree 4 (embreex).

Usage (after `rt-view bench --out bench-out`):
    pip install embreex numpy
    python3 bench/embree_primary.py bench-out [--runs 5]

For every bench-out/terrain_*.obj with its camera JSON, it loads the mesh,
builds Embree's BVH, casts one primary ray through each pixel centre (the
camera math of docs/conventions.md: perspective rays from C through
O + (ix+0.5)(w/W)·x − (iy+0.5)(h/H)·y), and prints the build time, the
median throughput in Mrays/s, the hit count (compare it with rt-view's) and
how many CPU seconds the casting used per wall second (embreex casts rays one
at a time with rtcIntersect1, on one thread).
"""
import argparse
import glob
import json
import os
import statistics
import time

import numpy as np
from embreex import rtcore_scene as rtcs
from embreex.mesh_construction import TriangleMesh


def load_obj(path):
    """Vertices (V,3) float32 and triangles (T,3) int32; faces fanned as rt-view does."""
    verts, tris = [], []
    with open(path) as f:
        for line in f:
            if line.startswith("v "):
                verts.append([float(x) for x in line.split()[1:4]])
            elif line.startswith("f "):
                idx = [int(c.split("/")[0]) - 1 for c in line.split()[1:]]
                for k in range(1, len(idx) - 1):
                    tris.append([idx[0], idx[k], idx[k + 1]])
    return np.array(verts, dtype=np.float32), np.array(tris, dtype=np.int32)


def primary_rays(cam):
    c = np.array(cam["position"], dtype=np.float64)
    coi = np.array(cam["center_of_interest"], dtype=np.float64)
    up = np.array(cam["up"], dtype=np.float64)
    z = (coi - c) / np.linalg.norm(coi - c)
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    W, H, near = cam["width"], cam["height"], cam["near"]
    ph = 2 * near * np.tan(np.radians(cam["fov_y"]) / 2)
    pw = ph * W / H
    ix, iy = np.meshgrid(np.arange(W) + 0.5, np.arange(H) + 0.5)
    right = (ix * (pw / W) - pw / 2).reshape(-1, 1)
    upward = (ph / 2 - iy * (ph / H)).reshape(-1, 1)
    dirs = near * z + right * x + upward * y
    origins = np.tile(c, (W * H, 1))
    return origins.astype(np.float32), dirs.astype(np.float32)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out", help="the folder `rt-view bench --out` wrote")
    ap.add_argument("--runs", type=int, default=5)
    args = ap.parse_args()
    print(f"{'mesh':>6} {'triangles':>10} {'build s':>9} {'Mrays/s':>9} {'hits':>9} {'cpu/wall':>9}")
    for obj in sorted(glob.glob(os.path.join(args.out, "terrain_*.obj")), key=os.path.getsize):
        label = os.path.basename(obj)[len("terrain_"):-len(".obj")]
        cam = json.load(open(obj[:-4] + ".json"))
        verts, tris = load_obj(obj)
        origins, dirs = primary_rays(cam)
        builds = []
        for _ in range(args.runs):
            t0 = time.perf_counter()
            scene = rtcs.EmbreeScene()
            TriangleMesh(scene, verts, tris)
            scene.run(origins[:1], dirs[:1])  # commits (builds the BVH) and casts one ray
            builds.append(time.perf_counter() - t0)
        times, cpu = [], []
        for _ in range(args.runs):
            w0, c0 = time.perf_counter(), time.process_time()
            ids = scene.run(origins, dirs)
            times.append(time.perf_counter() - w0)
            cpu.append((time.process_time() - c0) / times[-1])
        hits = int((ids >= 0).sum())
        mrays = len(origins) / statistics.median(times) / 1e6
        print(f"{label:>6} {len(tris):>10} {statistics.median(builds):>9.4f} {mrays:>9.3f} {hits:>9} {statistics.median(cpu):>9.2f}")


if __name__ == "__main__":
    main()
