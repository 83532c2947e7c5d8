#!/usr/bin/env python3
"""Cast the same rays as `rt-view bench` with Intel Embree 4 (embreex).

Usage (after `rt-view bench --out bench-out --threads 1,2`):
    pip install embreex numpy
    python3 bench/embree_primary.py bench-out [--runs 5] [--threads 1,2]

For every bench-out/terrain_*.obj with its camera JSON and bounce rays, and
for each thread count T, it measures:
  - the BVH build with T threads (Embree builds with TBB, which uses the CPUs
    the process may run on: the build runs in a child process allowed T CPUs).
    Only Embree's own work is timed: the scene commit (`rtcCommitScene`, which
    embreex runs on the first query), after `TriangleMesh` has copied the
    vertex and index arrays from Python into Embree's buffers, as a C program
    calling `rtcCommitScene` would see it;
  - the primary rays, one through each pixel centre (the camera math of
    docs/conventions.md: rays from C through O + (ix+0.5)(w/W)·x −
    (iy+0.5)(h/H)·y), and the incoherent bounce rays rt-view wrote
    (terrain_*.bounce: per ray six little-endian f32, origin and direction,
    and the u32 primitive rt-view hit), cast with rtcIntersect1 ray by ray.
    embreex casts on the calling thread, so T threads are T processes, each
    pinned to its own CPU with its own copy of the scene, casting a 1/T share;
    the time is the slowest one's.
and the memory: what the commit added and kept (Embree's BVH: the larger of
the C heap's growth, as glibc's `mallinfo2` counts blocks in use, which sees
small trees' memory even where freed memory is reused, and the resident
size's growth, which sees the blocks Embree maps itself for large trees)
plus the mesh's vertex and index buffers, per triangle, beside rt-view's
bytes per triangle (BVH plus mesh).
It prints medians, the hit counts (compare them with rt-view's), how many
bounce rays hit the same primitive in both, and, from bench-out/bench.csv,
rt-view's figures over Embree's for the same mesh and thread count.

Embree runs in its robust mode (RTC_SCENE_FLAG_ROBUST, which `embreex`
sets unless told not to: it "avoids optimizations that reduce arithmetic
accuracy", with a watertight triangle test), the accuracy rt-view's
watertight test always has, so like is compared with like. With
--no-robust the scenes are made without that flag, as Embree's C API
makes them by default: faster, and it lets a few rays through the edges
between triangles (its hit counts fall short of rt-view's).

With --embree-config CONFIG (say `max_isa=avx2`, rt-view's widest
instructions, where Embree would pick AVX-512 kernels on a CPU that has
it) Embree's device is made with that configuration string: `embreex`
makes its device with none, so the script compiles a small shim with the
C compiler (`cc`), which the dynamic loader puts in front of Embree's
`rtcNewDevice` (LD_PRELOAD), and runs itself again with it. Add
`verbose=1` to see which kernels Embree chose.

With --build-only it times the commits alone (no rays, no bounce files
needed), the counterpart of `rt-view bench --build-only`: run the two in
turn, several times, to compare builds on a machine whose speed drifts
(docs/performance.md, "The build beside Embree's commit").
"""
import argparse
import csv
import ctypes
import glob
import json
import multiprocessing as mp
import os
import statistics
import subprocess
import sys
import tempfile
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
    return np.ascontiguousarray(origins, dtype=np.float32), np.ascontiguousarray(dirs, dtype=np.float32)


def load_bounce(path):
    """Origins, directions (float32) and rt-view's primitive ids (uint32) of the bounce rays."""
    rec = np.fromfile(path, dtype=np.dtype([("ray", "<f4", 6), ("id", "<u4")]))
    rays = rec["ray"]
    return np.ascontiguousarray(rays[:, :3]), np.ascontiguousarray(rays[:, 3:]), rec["id"].astype(np.int64)


class _MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in
                "arena ordblks smblks hblks hblkhd usmblks fsmblks uordblks fordblks keepcost".split()]


def heap_in_use():
    """Bytes the C heap has handed out and not taken back (glibc's
    `mallinfo2`: in-use arena blocks plus mapped blocks), where Embree keeps
    its BVH. Unlike the resident size it does not miss memory that earlier
    work freed and the commit reused."""
    libc = ctypes.CDLL("libc.so.6")
    libc.mallinfo2.restype = _MallInfo2
    info = libc.mallinfo2()
    return info.uordblks + info.hblkhd


def resident_bytes():
    """The process's resident memory (Linux `/proc/self/statm`), in bytes."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def new_scene(verts, tris):
    """A committed Embree scene of the mesh, the seconds the commit took, and
    the memory the commit added and kept (bytes: its BVH).

    `TriangleMesh` copies the arrays into Embree's buffers in Python; the
    first `run` commits the scene (`rtcCommitScene`: the BVH build) and casts
    one ray, which is the only part timed.
    """
    scene = rtcs.EmbreeScene(robust=DATA["robust"])
    TriangleMesh(scene, verts, tris)
    one = np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32)
    heap, resident = heap_in_use(), resident_bytes()
    t0 = time.perf_counter()
    scene.run(*one)  # commits: builds the BVH
    seconds = time.perf_counter() - t0
    # Embree takes small trees' memory from the C heap and maps large
    # blocks itself: the heap's growth sees the first (where freed memory
    # was reused, the resident size does not grow), the resident growth
    # the second (mappings the heap does not count); the larger of the two.
    return scene, seconds, max(heap_in_use() - heap, resident_bytes() - resident)


# Set in the parent before forking; the children read them.
DATA = {}
# How the header names Embree's mode.
MODE = {True: "robust mode", False: "without RTC_SCENE_FLAG_ROBUST"}


def build_worker(cpus, runs, out):
    os.sched_setaffinity(0, cpus)
    times = []
    grown = []
    for _ in range(runs):
        scene, seconds, grew = new_scene(DATA["verts"], DATA["tris"])
        times.append(seconds)
        grown.append(grew)
        del scene
    out.put((statistics.median(times), statistics.median(grown)))


def cast_worker(cpu, share, runs, barrier, out):
    os.sched_setaffinity(0, {cpu})
    scene = new_scene(DATA["verts"], DATA["tris"])[0]
    result = {}
    for name in ("primary", "bounce"):
        origins, dirs = DATA[name]
        lo, hi = share * len(origins) // DATA["parts"], (share + 1) * len(origins) // DATA["parts"]
        o, d = origins[lo:hi], dirs[lo:hi]
        ids = scene.run(o, d)  # warm-up, and the hits
        times = []
        for _ in range(runs):
            barrier.wait()
            t0 = time.perf_counter()
            scene.run(o, d)
            times.append(time.perf_counter() - t0)
        result[name] = (times, ids)
    out.put((share, result))


def measure(threads, runs):
    ctx = mp.get_context("fork")
    out = ctx.Queue()
    cpus = sorted(os.sched_getaffinity(0))
    p = ctx.Process(target=build_worker, args=(set(cpus[:threads]), runs, out))
    p.start()
    build, grown = out.get()
    p.join()
    DATA["parts"] = threads
    barrier = ctx.Barrier(threads)
    procs = [ctx.Process(target=cast_worker, args=(cpus[i % len(cpus)], i, runs, barrier, out)) for i in range(threads)]
    for p in procs:
        p.start()
    parts = dict(out.get() for _ in procs)
    for p in procs:
        p.join()
    res = {"build": build, "grown": grown}
    for name in ("primary", "bounce"):
        # Run k took as long as its slowest process.
        walls = [max(parts[s][name][0][k] for s in parts) for k in range(runs)]
        ids = np.concatenate([parts[s][name][1] for s in sorted(parts)])
        res[name] = (len(DATA[name][0]) / statistics.median(walls) / 1e6, ids)
    return res


def build_only(out, threads, runs):
    """Embree's commit time per mesh and thread count (medians of `runs`)."""
    config = f", device config {device_config()}" if device_config() else ""
    print(f"Intel Embree 4 (embreex, {MODE[DATA['robust']]}{config}): the scene commit alone (rtcCommitScene), "
          f"medians of {runs}")
    objs = sorted(glob.glob(os.path.join(out, "terrain_*.obj")), key=os.path.getsize)
    if not objs:
        raise SystemExit(f"no terrain_*.obj in {out}: run `rt-view bench --out {out}` first")
    ctx = mp.get_context("fork")
    cpus = sorted(os.sched_getaffinity(0))
    for obj in objs:
        label = os.path.basename(obj)[len("terrain_"):-len(".obj")]
        DATA["verts"], DATA["tris"] = load_obj(obj)
        for t in threads:
            q = ctx.Queue()
            p = ctx.Process(target=build_worker, args=(set(cpus[:t]), runs, q))
            p.start()
            build, _ = q.get()
            p.join()
            print(f"terrain {label}: {len(DATA['tris'])} triangles, {t} thread(s): commit {build:.4f} s", flush=True)


# `rtcNewDevice` with the configuration in EMBREE_CONFIG, for embreex, whose
# device is made with none: the loader puts this in front of Embree's own.
SHIM = r"""
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
typedef void *(*new_device_t)(const char *);
void *rtcNewDevice(const char *config) {
    void *lib = dlopen(getenv("EMBREE_LIB"), RTLD_NOW | RTLD_NOLOAD);
    new_device_t real = lib ? (new_device_t)dlsym(lib, "rtcNewDevice") : 0;
    if (!real) {
        fprintf(stderr, "embree config shim: no rtcNewDevice in %s\n", getenv("EMBREE_LIB"));
        abort();
    }
    const char *wanted = getenv("EMBREE_CONFIG");
    return real(wanted ? wanted : config);
}
"""


def device_config():
    """The configuration Embree's device is made with here (None: embreex's own)."""
    shim = "embree-shim-" in os.environ.get("LD_PRELOAD", "")
    return os.environ.get("EMBREE_CONFIG") if shim else None


def rerun_with_config(config):
    """Runs this script again with Embree's device made with `config`."""
    import embreex
    libs = glob.glob(os.path.join(os.path.dirname(embreex.__file__), os.pardir, "embreex.libs", "libembree4*.so*"))
    if len(libs) != 1:
        raise SystemExit(f"--embree-config: expected one libembree4 beside embreex, found {libs}")
    folder = tempfile.mkdtemp(prefix="embree-shim-")
    source, shim = os.path.join(folder, "shim.c"), os.path.join(folder, "shim.so")
    with open(source, "w") as f:
        f.write(SHIM)
    try:
        subprocess.run(["cc", "-shared", "-fPIC", "-O2", "-o", shim, source, "-ldl"], check=True)
    except (OSError, subprocess.CalledProcessError) as e:
        raise SystemExit(f"--embree-config needs a C compiler (cc) to build its shim: {e}")
    env = dict(os.environ, EMBREE_CONFIG=config, EMBREE_LIB=os.path.realpath(libs[0]), LD_PRELOAD=shim)
    os.execve(sys.executable, [sys.executable] + sys.argv, env)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out", help="the folder `rt-view bench --out` wrote")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--threads", default="1,2", help="thread counts, comma-separated")
    ap.add_argument("--build-only", action="store_true", help="time the scene commits alone")
    ap.add_argument("--no-robust", action="store_true",
                    help="scenes without RTC_SCENE_FLAG_ROBUST (Embree's C API default; faster, not watertight)")
    ap.add_argument("--embree-config", help="Embree's device configuration, e.g. max_isa=avx2 (needs cc)")
    args = ap.parse_args()
    if args.embree_config and device_config() != args.embree_config:
        rerun_with_config(args.embree_config)
    DATA["robust"] = not args.no_robust
    threads = [int(t) for t in args.threads.split(",")]
    if args.build_only:
        build_only(args.out, threads, args.runs)
        return
    ours = {}
    bench_csv = os.path.join(args.out, "bench.csv")
    if os.path.exists(bench_csv):
        for row in csv.DictReader(open(bench_csv)):
            ours[(row["mesh"], int(row["threads"]))] = row
    config = f", device config {device_config()}" if device_config() else ""
    print(f"Intel Embree 4 (embreex, rtcIntersect1, {MODE[DATA['robust']]}{config}), medians of {args.runs} runs; "
          "Mrays/s; "
          "build s: the scene commit alone (rtcCommitScene), not embreex's copying of the arrays; "
          "B/tri: the memory the commit added and kept (its BVH: the larger of the C heap's growth, "
          "glibc mallinfo2, and the resident size's) plus the mesh's "
          "vertex and index buffers (12 bytes per vertex and per triangle), per triangle, beside "
          "rt-view's BVH plus mesh")
    print(f"{'mesh':>5} {'triangles':>10} {'threads':>7} {'build s':>8} {'B/tri':>6} {'primary':>8} {'bounce':>8} "
          f"{'hits':>8} {'b. hits':>8} {'same id':>8}   rt-view / Embree: {'build':>6} {'single':>7} {'packets':>8} "
          f"{'bounce':>7} {'B/tri':>6}")
    for obj in sorted(glob.glob(os.path.join(args.out, "terrain_*.obj")), key=os.path.getsize):
        label = os.path.basename(obj)[len("terrain_"):-len(".obj")]
        DATA["verts"], DATA["tris"] = load_obj(obj)
        DATA["primary"] = primary_rays(json.load(open(obj[:-4] + ".json")))
        bounce_path = obj[:-4] + ".bounce"
        if not os.path.exists(bounce_path):
            raise SystemExit(f"{bounce_path} is missing: run the current `rt-view bench` first")
        *rays, our_ids = load_bounce(bounce_path)
        DATA["bounce"] = tuple(rays)
        for t in threads:
            r = measure(t, args.runs)
            hits = int((r["primary"][1] >= 0).sum())
            b_ids = r["bounce"][1]
            b_hits = int((b_ids >= 0).sum())
            ours_ids = np.where(our_ids == 0xFFFFFFFF, -1, our_ids)
            same = float((b_ids == ours_ids).mean())
            mesh_bytes = 12 * (len(DATA["verts"]) + len(DATA["tris"]))
            per_tri = (r["grown"] + mesh_bytes) / len(DATA["tris"])
            line = (f"{label:>5} {len(DATA['tris']):>10} {t:>7} {r['build']:>8.4f} {per_tri:>6.1f} "
                    f"{r['primary'][0]:>8.3f} {r['bounce'][0]:>8.3f} {hits:>8} {b_hits:>8} {same:>8.5f}")
            o = ours.get((label, t))
            if o:
                line += (f"   {' ':>16} {r['build'] / float(o['bvh_build_s']):>5.2f}x "
                         f"{float(o['primary_single_mrays_per_s']) / r['primary'][0]:>6.2f}x "
                         f"{float(o['primary_packets_mrays_per_s']) / r['primary'][0]:>7.2f}x "
                         f"{float(o['bounce_mrays_per_s']) / r['bounce'][0]:>6.2f}x "
                         f"{float(o['bytes_per_triangle']) / per_tri:>5.2f}x")
            print(line, flush=True)


if __name__ == "__main__":
    main()
