#!/usr/bin/env python3
"""Time to a clean image: how long rt-view, Mitsuba 3 and Blender Cycles
each take to reach the same error against one high-sample reference, side
by side in one run.

    venv-bpy/bin/python -m pip install bpy==5.0.1 numpy mitsuba   (Python 3.11)
    scripts/get_oidn.sh
    cargo build --release -p rt-view
    venv-bpy/bin/python bench/time_to_clean.py --threads 2

Scenes: every scene in `scenes/` with global illumination, or those named;
the conversions are bench/mitsuba_compare.py's (Mitsuba) and
bench/common/cycles.py's (Cycles), both from `rt-view export` JSON. A scene
one of them cannot convert is left out with the reason, and the run goes
on. Each scene is rendered at `--size` (small, so that the run fits in
minutes).

- **Reference:** Mitsuba `llvm_ad_rgb` (the independent sampler, `path`,
  or `volpath` for media; media whose mean free path differs between
  channels are rendered a channel at a time, as bench/mitsuba_compare.py
  does), `--reference-spp` samples in two halves of different seeds. The
  mean is the reference; a quarter of the mean squared difference of the
  halves is the reference's own noise, subtracted from every squared error
  below (the halves are independent of the images judged).
- **Error:** RMSE of linear radiance clamped to [0, 1] (as a display shows
  it: an unclamped light of radiance 17 would outweigh the room), all
  pixels and channels; with the reference noise taken out as above.
  Denoised images are also judged by SSIM (bench/common/images.py) of the
  sRGB-encoded luminance.
- **Methods**, each at every count of `--spp` (a ladder):
  rt-view plain with the `stratified` and the `sobol` sampler; rt-view
  adaptive (`sobol`, `--noise-threshold` t = `--threshold-at-64`·√(64/N)
  at N samples, the count as the cap, `--min-samples` min(16, N)); rt-view
  denoised (`sobol` + `--denoise`, OIDN fed albedo and normal); Mitsuba
  `llvm_ad_rgb` and `scalar_rgb` (their defaults: the independent
  sampler); Cycles plain (its default sampling pattern), Cycles adaptive
  (the same t as rt-view's, `adaptive_min_samples` min(16, N)) and Cycles
  + OIDN (plain sampling, OIDN fed albedo and normal, Cycles' default
  prefilter).
- **Time** is what the engine does, not Python's copying: rt-view's own
  render time from its stderr (`… in T s`, after scene load and BVH build)
  plus OIDN's (`denoised with OIDN in T s`); Mitsuba `mi.render` until its
  result is evaluated (the first render of a variant, which compiles its
  kernels, is not timed); Cycles `bpy.ops.render.render` (scene sync,
  render, denoising and the 32-bit EXR write of `--size` pixels; the first
  render, which loads kernels, is not timed). Every method runs on
  `--threads` threads.
- **Runs:** each count is rendered `--runs` times with different seeds,
  the methods taking turns (so load on a shared machine falls on all of
  them alike); the median time and the root-mean of the squared errors
  count. A method stops climbing the ladder once it is below the smallest
  target, or once its next count would take longer than
  `--max-render-s`.
- **Targets:** the error of Mitsuba `llvm_ad_rgb` at 64 and at 1024
  samples (each method's time to it: log-log interpolation of time against
  error between the two counts around it; past the last count measured,
  the last segment's slope extended, marked `~`; a denoised method, whose
  error levels off into bias, is never extended: `—`).

Writes `--out`/<scene>/report.md (every measurement), `--out`/summary.md
(the times to each target and the ratios), results.json and, per scene, a
strip of small PNGs (reference, then each method at `--picture-spp`).
"""

import argparse
import json
import math
import os
import re
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mitsuba_compare  # noqa: E402  (the Mitsuba conversion)
from common import cycles as cycles_scene  # noqa: E402
from common import images  # noqa: E402

DEFAULT_SCENES = ["cornell_box", "caustic", "interreflection", "subsurface", "translucent_slab", "skin_mesh"]


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scenes", nargs="*", help="scene files (default: the GI and subsurface scenes listed in --all)")
    p.add_argument("--all", action="store_true", help="every scene of scenes/ with global illumination")
    p.add_argument("--size", default="96x96", help="image size WxH")
    p.add_argument("--spp", default="4,16,64,256", help="the ladder of sample counts")
    p.add_argument("--reference-spp", type=int, default=2048)
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--threads", type=int, default=os.cpu_count())
    p.add_argument("--threshold-at-64", type=float, default=0.04, help="adaptive noise threshold at 64 spp")
    p.add_argument("--max-render-s", type=float, default=15.0, help="a method stops before a render this long")
    p.add_argument("--methods", help="comma-separated subset of the methods (labels as in the report)")
    p.add_argument("--picture-spp", type=int, default=16)
    p.add_argument("--rt-view", default="target/release/rt-view")
    p.add_argument("--out", default="time-to-clean-out")
    p.add_argument("--summary-of", nargs="*", metavar="DIR",
                   help="render nothing: write the summary of earlier runs' scene folders (their result.json)")
    return p.parse_args()


def gi_scenes(folder, rt_view, out):
    """The scenes of `folder` whose export has global illumination."""
    found = []
    for name in sorted(os.listdir(folder)):
        if not name.endswith(".ron"):
            continue
        path = os.path.join(folder, name)
        export = os.path.join(out, "exports", name[:-4] + ".json")
        os.makedirs(os.path.dirname(export), exist_ok=True)
        done = subprocess.run([rt_view, "export", path, "-o", export], capture_output=True)
        if done.returncode == 0:
            with open(export) as f:
                if json.load(f).get("global_illumination") is not None:
                    found.append(path)
    return found


class Skip(Exception):
    """A scene or a method that cannot be run, and why."""


def convert(fn, *a, **k):
    """Calls a converter that exits on what it cannot convert; raises Skip."""
    try:
        return fn(*a, **k)
    except SystemExit as e:
        raise Skip(str(e.code)) from None


class RtView:
    def __init__(self, args, scene, folder, width, height):
        self.args, self.scene, self.folder = args, scene, folder
        self.size = ["--width", str(width), "--height", str(height)]
        self.env = dict(os.environ, RAYON_NUM_THREADS=str(args.threads))

    def render(self, options, spp, seed, mi):
        out = os.path.join(self.folder, "rt.exr")
        command = [self.args.rt_view, "render", self.scene, "-o", out, "--spp", str(spp), "--seed", str(seed)]
        done = subprocess.run(command + self.size + options, env=self.env, capture_output=True, text=True)
        if done.returncode != 0:
            raise Skip(f"rt-view failed: {done.stderr.strip()[-300:]}")
        took = float(re.search(r"spp\) in ([0-9.]+) s", done.stderr).group(1))
        if "--denoise" in options:
            oidn = re.search(r"denoised with OIDN in ([0-9.]+) s", done.stderr)
            if not oidn:
                raise Skip(f"rt-view did not denoise (OIDN missing? run scripts/get_oidn.sh): {done.stderr.strip()[-300:]}")
            took += float(oidn.group(1))
        mi.set_variant("scalar_rgb")
        return mitsuba_compare.read_exr(mi, out), took


class Mitsuba:
    def __init__(self, args, desc, folder, width, height):
        import drjit as dr
        import mitsuba as mi

        self.dr, self.mi = dr, mi
        self.args, self.desc, self.folder = args, desc, folder
        self.width, self.height = width, height
        self.scenes = {}

    def load(self, variant, split=False):
        key = (variant, split)
        if key not in self.scenes:
            self.mi.set_variant(variant)
            self.dr.set_thread_count(self.args.threads)
            descs = (
                [mitsuba_compare.one_channel(self.desc, c) for c in range(3)]
                if split
                else [self.desc]
            )
            self.scenes[key] = [
                self.mi.load_dict(
                    convert(mitsuba_compare.mitsuba_scene, self.mi, d, self.folder, self.width, self.height, 400.0)
                )
                for d in descs
            ]
            self.render(variant, 1, 999, split)  # compiles the kernels: not timed
        self.mi.set_variant(variant)
        return self.scenes[key]

    def render(self, variant, spp, seed, split=False):
        scenes = self.load(variant, split)
        mi, dr = self.mi, self.dr
        start = time.perf_counter()
        results = []
        for s in scenes:
            image = mi.render(s, spp=spp, seed=seed)
            dr.eval(image)
            dr.sync_thread()
            results.append(image)
        took = time.perf_counter() - start
        if split:
            pixels = np.stack([np.array(results[c], dtype=np.float64)[:, :, c] for c in range(3)], axis=2)
        else:
            pixels = np.array(results[0], dtype=np.float64)[:, :, :3]
        return pixels, took


class Cycles:
    def __init__(self, args, desc, folder, width, height):
        try:
            import bpy
        except ImportError:
            raise Skip("the bpy module is not installed (pip install bpy==5.0.1, Python 3.11)") from None

        self.bpy, self.folder = bpy, folder
        self.scene = convert(cycles_scene.scene_from_export, bpy, desc, folder, width, height, args.threads)
        self.mode = None
        self.render(None, 1, 999)  # loads the kernels: not timed

    def render(self, mode, spp, seed, threshold=None):
        c = self.scene.cycles
        c.use_adaptive_sampling = mode == "adaptive"
        if mode == "adaptive":
            c.adaptive_threshold = threshold
            c.adaptive_min_samples = min(16, spp)
        c.use_denoising = mode == "oidn"
        if mode == "oidn":
            c.denoiser = "OPENIMAGEDENOISE"
            c.denoising_input_passes = "RGB_ALBEDO_NORMAL"
        out = os.path.join(self.folder, "cycles.exr")
        took = cycles_scene.render(self.bpy, self.scene, out, spp, seed)
        return cycles_scene.read_exr(self.bpy, out), took


def methods(args):
    """(label, engine, how) of every method, in the order they take turns."""
    t = lambda n: args.threshold_at_64 * math.sqrt(64.0 / n)  # noqa: E731
    return [
        ("rt-view stratified", "rt", lambda n: ["--sampler", "stratified"]),
        ("rt-view sobol", "rt", lambda n: ["--sampler", "sobol"]),
        ("rt-view adaptive", "rt", lambda n: ["--sampler", "sobol", "--noise-threshold", f"{t(n):.5f}",
                                              "--min-samples", str(min(16, n))]),
        ("rt-view denoised", "rt", lambda n: ["--sampler", "sobol", "--denoise"]),
        ("Mitsuba llvm_ad_rgb", "mi", "llvm_ad_rgb"),
        ("Mitsuba scalar_rgb", "mi", "scalar_rgb"),
        ("Cycles", "cy", None),
        ("Cycles adaptive", "cy", "adaptive"),
        ("Cycles + OIDN", "cy", "oidn"),
    ], t


def targets_of(results):
    """The target errors: Mitsuba llvm_ad_rgb's RMSE at 64 and at 1024 spp;
    where the ladder stops short of 1024, its error at the largest count
    measured scaled by √(count/1024) (the independent sampler's error falls
    as 1/√spp)."""
    llvm = {r[0]: r[2] for r in results.get("Mitsuba llvm_ad_rgb", [])}
    targets = {}
    if 64 in llvm:
        targets[64] = llvm[64]
    if 1024 in llvm:
        targets[1024] = llvm[1024]
    elif llvm and max(llvm) >= 64:
        top = max(llvm)
        targets[1024] = llvm[top] * math.sqrt(top / 1024)
    return targets


def time_to(points, target, extend=True):
    """(seconds, how) to reach `target` from (time, error) points of a
    ladder: log-log interpolation between the two points around it; past
    the last, the last segment extended (how = '~') when `extend`."""
    points = sorted(points)
    for (t0, e0), (t1, e1) in zip(points, points[1:]):
        if e0 >= target >= e1 and e0 > e1:
            s = (math.log(target) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + s * (math.log(t1) - math.log(t0))), ""
    if points and points[0][1] <= target:
        return points[0][0], "≤"
    if extend and len(points) >= 2:
        (t0, e0), (t1, e1) = points[-2], points[-1]
        if e1 < e0 and e1 > 0:
            slope = (math.log(t1) - math.log(t0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t1) + slope * (math.log(target) - math.log(e1))), "~"
    return None, "—"


def run_scene(args, scene_path, width, height, counts):
    import mitsuba as mi

    name = os.path.splitext(os.path.basename(scene_path))[0]
    folder = os.path.abspath(os.path.join(args.out, name))
    desc = mitsuba_compare.export_scene(args.rt_view, scene_path, folder)
    if desc.get("global_illumination") is None:
        raise Skip("no global illumination")
    rt = RtView(args, scene_path, folder, width, height)
    mitsuba = Mitsuba(args, desc, folder, width, height)
    split = mitsuba_compare.chromatic(desc)
    print(f"{name}: reference, Mitsuba llvm_ad_rgb {args.reference_spp} spp in two halves"
          f"{' (a channel at a time)' if split else ''} ...", flush=True)
    start = time.perf_counter()
    half_a, _ = mitsuba.render("llvm_ad_rgb", args.reference_spp // 2, 100001, split)
    half_b, _ = mitsuba.render("llvm_ad_rgb", args.reference_spp // 2, 100002, split)
    reference_s = time.perf_counter() - start
    reference = 0.5 * (half_a + half_b)
    ref_noise2 = float(np.mean((np.clip(half_a, 0, 1) - np.clip(half_b, 0, 1)) ** 2)) / 4
    ref_lum = images.srgb_luminance(reference)
    print(f"  reference in {reference_s:.0f} s; its own RMSE ≈ {math.sqrt(ref_noise2):.5f}", flush=True)

    notes = []
    all_methods, threshold = methods(args)
    wanted = set(args.methods.split(",")) if args.methods else None
    cycles = None
    if any(engine == "cy" and (wanted is None or label in wanted) for label, engine, _ in all_methods):
        try:
            cycles = Cycles(args, desc, folder, width, height)
        except Skip as e:
            notes.append(f"Cycles left out: {e}")
    chosen = [m for m in all_methods if (wanted is None or m[0] in wanted) and not (m[1] == "cy" and cycles is None)]
    for label, engine, how in chosen:
        if engine == "mi":
            try:
                mitsuba.load(how)
            except Skip as e:
                notes.append(f"{label} left out: {e}")
    chosen = [m for m in chosen if not (m[1] == "mi" and (m[2], False) not in mitsuba.scenes)]

    def render(label, engine, how, n, seed):
        if engine == "rt":
            return rt.render(how(n), n, seed, mi)
        if engine == "mi":
            return mitsuba.render(how, n, seed)
        return cycles.render(how, n, seed, threshold(n))

    results = {label: [] for label, _, _ in chosen}  # (spp, median s, rmse, ssim)
    active = {label for label, _, _ in chosen}
    pictures = {}
    smallest_target = None
    for n in counts:
        runs = {label: ([], [], []) for label in active}
        for run in range(args.runs):
            for label, engine, how in chosen:
                if label not in active:
                    continue
                image, took = render(label, engine, how, n, 1 + run + 1000 * n)
                err2 = max(float(np.mean((np.clip(image, 0, 1) - np.clip(reference, 0, 1)) ** 2)) - ref_noise2, 1e-12)
                runs[label][0].append(took)
                runs[label][1].append(err2)
                runs[label][2].append(images.ssim(images.srgb_luminance(image), ref_lum))
                if n == args.picture_spp and run == 0:
                    pictures[label] = image
        for label in [m[0] for m in chosen if m[0] in active]:
            times, errs, ssims = runs[label]
            row = (n, float(np.median(times)), math.sqrt(float(np.mean(errs))), float(np.mean(ssims)))
            results[label].append(row)
            print(f"  {label:20s} {n:5d} spp: {row[1]:8.3f} s  RMSE {row[2]:.5f}  SSIM {row[3]:.4f}", flush=True)
        # Targets once Mitsuba llvm has measured them; a method below the
        # smallest one, or whose next render would take too long, stops.
        if n == counts[-1] or n == 1024:
            smallest_target = targets_of(results).get(1024)
        for label in list(active):
            if label == "Mitsuba llvm_ad_rgb" and n < min(1024, counts[-1]):
                continue
            last = results[label][-1]
            if smallest_target is not None and last[2] <= smallest_target:
                active.discard(label)
            elif last[1] * 4 > args.max_render_s and n != counts[-1]:
                active.discard(label)
                notes.append(f"{label}: stopped after {n} spp (the next count would take about {4 * last[1]:.0f} s)")
    targets = targets_of(results)
    if 1024 not in counts and 1024 in targets:
        notes.append(f"the 1024-spp target is Mitsuba llvm_ad_rgb's RMSE at {counts[-1]} spp × √({counts[-1]}/1024) "
                     "(its independent sampler's error falls as 1/√spp), not measured")
    to_target = {}
    for label, rows in results.items():
        for k, target in targets.items():
            to_target[(label, k)] = time_to([(r[1], r[2]) for r in rows], target, extend="denoised" not in label and "OIDN" not in label)

    lines = [f"# {name}: time to a clean image, {width}×{height}, {args.threads} threads", ""]
    lines.append(f"Reference: Mitsuba llvm_ad_rgb, {args.reference_spp} spp ({reference_s:.0f} s), own RMSE "
                 f"{math.sqrt(ref_noise2):.5f} (taken out of every error below).")
    lines.append("Targets: " + ", ".join(f"{t:.5f} (Mitsuba llvm_ad_rgb at {k} spp)" for k, t in targets.items()) + ".")
    lines += ["", "| method | spp | time (s) | RMSE | SSIM |", "|---|---:|---:|---:|---:|"]
    for label, rows in results.items():
        for n, t, e, s in rows:
            lines.append(f"| {label} | {n} | {t:.3f} | {e:.5f} | {s:.4f} |")
    lines += ["", "| method | " + " | ".join(f"s to RMSE {t:.4f} ({k} spp)" for k, t in targets.items()) + " |",
              "|---|" + "---:|" * len(targets)]
    for label in results:
        cells = []
        for k in targets:
            sec, how = to_target[(label, k)]
            cells.append("—" if sec is None else f"{how}{sec:.3f}")
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    lines += [""] + [f"- {n}" for n in notes]
    report = "\n".join(lines) + "\n"
    print(report, flush=True)
    with open(os.path.join(folder, "report.md"), "w") as f:
        f.write(report)

    if pictures:
        strip = [images.srgb(reference)] + [images.srgb(pictures[label]) for label in results if label in pictures]
        mi.set_variant("scalar_rgb")
        mi.Bitmap(np.concatenate(strip, axis=1)).write(os.path.join(folder, f"strip-{args.picture_spp}spp.png"))
        labels = ["reference"] + [label for label in results if label in pictures]
        with open(os.path.join(folder, f"strip-{args.picture_spp}spp.txt"), "w") as f:
            f.write(" | ".join(labels) + "\n")
    result = {
        "scene": name,
        "reference_s": reference_s,
        "reference_rmse": math.sqrt(ref_noise2),
        "targets": targets,
        "results": results,
        "to_target": {f"{label}@{k}": v for (label, k), v in to_target.items()},
        "notes": notes,
    }
    with open(os.path.join(folder, "result.json"), "w") as f:
        json.dump(result, f, indent=1)
    return result


def ratio(a, b):
    if a is None or b is None or a[0] is None or b[0] is None:
        return "—"
    mark = "~" if "~" in (a[1], b[1]) else ""
    return f"{mark}{a[0] / b[0]:.2f}"


def main():
    args = parse_args()
    mitsuba_compare.use_llvm19()  # before drjit is imported
    width, height = (int(v) for v in args.size.split("x"))
    counts = [int(n) for n in args.spp.split(",")]
    os.makedirs(args.out, exist_ok=True)
    if args.scenes:
        scenes = args.scenes
    elif args.all:
        scenes = gi_scenes("scenes", args.rt_view, args.out)
    else:
        scenes = [os.path.join("scenes", s + ".ron") for s in DEFAULT_SCENES]
    done, skipped = [], []
    started = time.perf_counter()
    if args.summary_of is not None:
        scenes = []
        for folder in args.summary_of:
            with open(os.path.join(folder, "result.json")) as f:
                d = json.load(f)
            d["targets"] = {int(k): v for k, v in d["targets"].items()}
            done.append(d)
    for scene in scenes:
        try:
            done.append(run_scene(args, scene, width, height, counts))
        except Skip as e:
            print(f"{scene}: left out: {e}", flush=True)
            skipped.append((scene, str(e)))
    with open(os.path.join(args.out, "results.json"), "w") as f:
        json.dump({"args": vars(args), "scenes": done, "skipped": skipped}, f, indent=1, default=str)

    load = os.getloadavg()
    lines = [
        f"# Time to a clean image: {width}×{height}, {args.threads} threads, {args.runs} runs each, medians",
        "",
        f"Machine: {os.cpu_count()} cores, load average {load[0]:.1f} at the end; whole run "
        f"{time.perf_counter() - started:.0f} s.",
        "",
        "Ratios: rt-view's time to the target over the other's (≤ 0.66 is the goal for plain, ≤ 1 for denoised "
        "against Cycles + OIDN); `~` extrapolated, `—` not reached.",
        "",
        "| scene | target | rt-view sobol / Mitsuba llvm | sobol / Cycles | stratified / Mitsuba llvm | "
        "adaptive / Cycles adaptive | denoised / Cycles + OIDN | denoised SSIM at the target spp |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for d in done:
        tt = d["to_target"]
        for k, target in d["targets"].items():
            g = lambda label: tt.get(f"{label}@{k}")  # noqa: E731
            den = [r for r in d["results"].get("rt-view denoised", []) if r[0] == k]
            cyd = [r for r in d["results"].get("Cycles + OIDN", []) if r[0] == k]
            ssim = f"{den[0][3]:.3f}" if den else "—"
            ssim += f" (Cycles {cyd[0][3]:.3f})" if cyd else ""
            lines.append(
                f"| {d['scene']} | {target:.4f} ({k} spp) | {ratio(g('rt-view sobol'), g('Mitsuba llvm_ad_rgb'))} | "
                f"{ratio(g('rt-view sobol'), g('Cycles'))} | {ratio(g('rt-view stratified'), g('Mitsuba llvm_ad_rgb'))} | "
                f"{ratio(g('rt-view adaptive'), g('Cycles adaptive'))} | {ratio(g('rt-view denoised'), g('Cycles + OIDN'))} | "
                f"{ssim} |"
            )
    lines += [""] + [f"- {s}: left out: {why}" for s, why in skipped]
    summary = "\n".join(lines) + "\n"
    print(summary)
    with open(os.path.join(args.out, "summary.md"), "w") as f:
        f.write(summary)


if __name__ == "__main__":
    main()
