#!/usr/bin/env python3
"""How long the viewer takes, after a camera move, to show a denoised
full-resolution image and an image without visible grain.

    apt-get install xvfb xdotool x11-apps
    scripts/get_oidn.sh
    cargo build --release -p rt-view
    venv-bpy/bin/python bench/viewer_timing.py scenes/cornell_box.ron \\
        --denoise-at 150,400 --threads 2

The viewer runs under its own Xvfb with its trace on (`RT_VIEW_TRACE`,
crates/rt-view/src/viewer/trace.rs) and `RT_VIEW_TRACE_IMAGES`, which makes
it write the linear image on screen to a file each time every row of it is
at the same samples per pixel and it changed. Once the first full image is on
screen (`--denoise-at X,Y` ticks the denoise box first: the box's place in the
window, found on the screenshot the script writes, `window.png`), Space
stops it (so the move starts from an idle viewer) and the image is
dragged `--drag-px` pixels sideways, 5 pixels every 33 ms, as a person
orbits, and released. The
release is the trace's line of the full render's job after the drag (the
first frame that job is current in: at most a frame after the mouse button
went up). Every image written after it is compared with a reference:

- the reference is Mitsuba 3 `llvm_ad_rgb` of the same view (the camera
  the trace gives the job, written into a copy of the scene; each run's
  own, as the drag's events may not land alike and converted
  as bench/mitsuba_compare.py does), `--reference-spp` samples in two
  halves; the error is the RMSE of linear radiance clamped to [0, 1] with
  the reference's own noise taken out (as bench/time_to_clean.py does).
- **without visible grain** is an RMSE below `--threshold`, 0.0036 by
  default: one step of 8-bit sRGB at mid-grey (d(linear)/d(sRGB) ≈ 0.93
  at 0.5, over 255), so the noise left is under the display's own
  quantisation in the mid-tones.
- **denoised full-resolution image**: with the denoise box ticked, the
  last image written at the first pass's samples (the noisy first pass
  streams in, then its denoised image replaces it whole).

Writes `--out`/report.md and the trace; the images written are deleted
unless `--keep-images`.
"""

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import mitsuba_compare  # noqa: E402


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene", nargs="?", default="scenes/cornell_box.ron")
    p.add_argument("--rt-view", default="target/release/rt-view")
    p.add_argument("--threads", type=int, default=os.cpu_count())
    p.add_argument("--scale", type=float, default=1.0, help="the viewer's resolution scale")
    p.add_argument("--denoise-at", help="X,Y of the denoise box in the window (see window.png)")
    p.add_argument("--sampler", choices=["scene", "stratified", "sobol"], default="scene",
                   help="the sampler the viewer renders with (a copy of the scene with `sampler` set)")
    p.add_argument("--spp", type=int, default=256, help="the samples the viewer renders to (the scene's)")
    p.add_argument("--reference-spp", type=int, default=1024)
    p.add_argument("--threshold", type=float, default=0.0036, help="RMSE below which no grain is visible")
    p.add_argument("--timeout", type=float, default=300.0, help="seconds to wait for each render")
    p.add_argument("--drag-px", type=int, default=40, help="how far the drag orbits, in screen pixels")
    p.add_argument("--display", default=":57")
    p.add_argument("--out", default="viewer-timing-out")
    p.add_argument("--keep-images", action="store_true")
    return p.parse_args()


def read_trace(path):
    if not os.path.exists(path):
        return []
    with open(path) as f:
        text = f.read()
    whole = text[: text.rfind("\n") + 1]
    return [json.loads(line) for line in whole.splitlines() if line.strip()]


class Viewer:
    def __init__(self, args, out):
        self.args, self.out = args, out
        self.trace = os.path.join(out, "trace.jsonl")
        self.images = os.path.join(out, "images")
        os.makedirs(self.images, exist_ok=True)
        os.makedirs(os.path.join(out, "state"), exist_ok=True)
        with open(os.path.join(out, "state", "app.ron"), "w") as f:
            f.write(json.dumps({"app": f"(resolution_scale: {args.scale!r})"}))
        self.xvfb = subprocess.Popen(["Xvfb", args.display, "-screen", "0", "1280x800x24", "-nolisten", "tcp"],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        time.sleep(1.0)
        env = dict(os.environ, DISPLAY=args.display, RT_VIEW_TRACE=self.trace, RT_VIEW_TRACE_IMAGES=self.images,
                   RT_VIEW_CONFIG_DIR=os.path.join(out, "state"), RAYON_NUM_THREADS=str(args.threads))
        env.pop("WAYLAND_DISPLAY", None)
        self.log = open(os.path.join(out, "viewer.log"), "w")
        self.child = subprocess.Popen([os.path.abspath(args.rt_view), os.path.abspath(args.scene)], cwd=out, env=env,
                                      stdout=self.log, stderr=self.log)
        self.wait("the first frame", 60, lambda lines: any("frame" in l for l in lines))
        deadline = time.time() + 20
        while True:
            found = self.xdotool("search", "--onlyvisible", "--name", "^rt-view$", check=False)
            if found.strip():
                self.window = found.split()[0]
                break
            if time.time() > deadline:
                sys.exit("the window was never mapped")
            time.sleep(0.05)
        geometry = self.xdotool("getwindowgeometry", "--shell", self.window)
        g = dict(line.split("=") for line in geometry.split())
        self.rect = [int(g["X"]), int(g["Y"]), int(g["WIDTH"]), int(g["HEIGHT"])]

    def xdotool(self, *a, check=True):
        done = subprocess.run(["xdotool", *a], env=dict(os.environ, DISPLAY=self.args.display),
                              capture_output=True, text=True)
        if check and done.returncode != 0:
            sys.exit(f"xdotool {a}: {done.stderr}")
        return done.stdout

    def screenshot(self, path):
        """The screen as a PNG (xwd's dump of a 24-bit TrueColor screen, read here)."""
        import mitsuba as mi

        data = subprocess.run(["xwd", "-root", "-display", self.args.display], capture_output=True, check=True).stdout
        h = np.frombuffer(data[:100], dtype=">u4")
        header_size, width, height, byte_order, bpp, stride, ncolors = h[0], h[4], h[5], h[7], h[11], h[12], h[19]
        if bpp not in (24, 32):
            print(f"warning: {bpp} bits a pixel: no screenshot", file=sys.stderr)
            return
        start, step = int(header_size) + 12 * int(ncolors), int(bpp) // 8
        pixels = np.frombuffer(data[start : start + int(stride) * int(height)], dtype=np.uint8)
        pixels = pixels.reshape(int(height), int(stride))[:, : int(width) * step].reshape(int(height), int(width), step)
        rgb = pixels[:, :, [2, 1, 0]] if byte_order == 0 else pixels[:, :, [step - 3, step - 2, step - 1]]
        if not mi.variant():
            mi.set_variant("scalar_rgb")
        mi.Bitmap(np.ascontiguousarray(rgb)).write(path)

    def lines(self):
        return read_trace(self.trace)

    def wait(self, what, seconds, done):
        deadline = time.time() + seconds
        while True:
            lines = self.lines()
            if done(lines):
                return lines
            if self.child.poll() is not None:
                sys.exit(f"the viewer exited while waiting for {what}; see {self.out}/viewer.log")
            if time.time() > deadline:
                sys.exit(f"timed out waiting for {what}")
            time.sleep(0.1)

    def finished(self, generation, spp):
        """Whether the canvas of `generation` is at `spp` samples everywhere."""
        return lambda lines: any(
            l.get("canvas") == generation and l.get("samples") == [spp, spp] for l in lines if "frame" in l
        )

    def close(self):
        if self.child.poll() is None:
            self.child.terminate()
        try:
            self.child.wait(10)
        except subprocess.TimeoutExpired:
            self.child.kill()
        self.xvfb.terminate()
        self.xvfb.wait()
        self.log.close()


def full_jobs(lines):
    return [l for l in lines if "job" in l and l["kind"] == "full"]


def scene_with_camera(scene, camera, path):
    """A copy of `scene` whose camera is `camera` (the trace's)."""
    with open(scene) as f:
        text = f.read()
    vec = lambda v: "(" + ", ".join(repr(float(x)) for x in v) + ")"  # noqa: E731
    for key in ("position", "center_of_interest", "up"):
        text, n = re.subn(rf"(\b{key}:\s*)\([^)]*\)", lambda m: m.group(1) + vec(camera[key]), text, count=1)
        if n != 1:
            sys.exit(f"{scene}: no camera {key} to replace")
    text = re.sub(r"(\bfov_y:\s*)[0-9.eE+-]+", lambda m: m.group(1) + repr(float(camera["fov_y"])), text, count=1)
    base = os.path.dirname(os.path.abspath(scene))
    text = re.sub(r'(file:\s*)"([^"/][^"]*)"', lambda m: f'{m.group(1)}"{os.path.join(base, m.group(2))}"', text)
    with open(path, "w") as f:
        f.write(text)


def reference(args, scene, out, width, height):
    """Mitsuba llvm_ad_rgb's image of `scene` in two halves: (mean, the
    mean's own squared error, clamped)."""
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    dr.set_thread_count(args.threads)
    desc = mitsuba_compare.export_scene(args.rt_view, scene, os.path.join(out, "mitsuba"))
    s = mi.load_dict(mitsuba_compare.mitsuba_scene(mi, desc, os.path.join(out, "mitsuba"), width, height, 400.0))
    halves = [np.array(mi.render(s, spp=args.reference_spp // 2, seed=200 + k), dtype=np.float64)[:, :, :3]
              for k in range(2)]
    noise2 = float(np.mean((np.clip(halves[0], 0, 1) - np.clip(halves[1], 0, 1)) ** 2)) / 4
    return 0.5 * (halves[0] + halves[1]), noise2


def measure(args, out, denoise):
    """Runs the viewer once; returns (the full job after the drag, its
    images: (seconds after the release, samples, path))."""
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    v = Viewer(args, out)
    try:
        v.screenshot(os.path.join(out, "window.png"))
        v.xdotool("windowfocus", "--sync", v.window)
        time.sleep(1.0)
        if denoise:
            # A click X drops (a window still settling, a loaded machine)
            # is tried again: ticking the box starts a new full job.
            x, y = (int(c) for c in args.denoise_at.split(","))
            for _ in range(5):
                v.xdotool("mousemove", str(v.rect[0] + x), str(v.rect[1] + y), "click", "1")
                try:
                    v.wait("the denoising job", 5, lambda ls: len(full_jobs(ls)) >= 2)
                    break
                except SystemExit:
                    continue
            else:
                sys.exit("the denoise box never ticked: is --denoise-at its place (see window.png)?")
        # The first full image whole (with the box ticked, of the job that
        # started), then Space stops that render, so the move starts from
        # an idle viewer.
        v.wait("a first full job", 60, lambda lines: bool(full_jobs(lines)))
        job = full_jobs(v.lines())[-1]["job"]
        v.wait("the first full image", args.timeout, lambda ls: any(
            l.get("canvas") == job and l.get("image") for l in ls if "frame" in l))
        v.xdotool("windowfocus", "--sync", v.window)
        v.xdotool("key", "space")
        time.sleep(1.0)
        before = full_jobs(v.lines())[-1]["job"]
        v.screenshot(os.path.join(out, "before.png"))
        # Drag-orbit sideways in steps of 5 px every 33 ms, and release.
        x0, y0 = v.rect[0] + 300 + (v.rect[2] - 300) // 2, v.rect[1] + (v.rect[3] - 24) // 2
        drag = ["mousemove", str(x0), str(y0), "mousedown", "1"]
        for _ in range(max(1, args.drag_px // 5)):
            drag += ["mousemove_relative", "5", "0", "sleep", "0.033"]
        drag += ["mouseup", "1"]
        for _ in range(3):
            v.xdotool(*drag)
            try:
                lines = v.wait("the full render after the drag", 30,
                               lambda ls: any(j["job"] > before for j in full_jobs(ls)))
                break
            except SystemExit:
                continue
        else:
            sys.exit("the drag never moved the camera")
        job = [j for j in full_jobs(lines) if j["job"] > before][-1]
        # Later full jobs would mean the move went on: take the last.
        lines = v.wait("the render after the drag to finish", args.timeout, v.finished(job["job"], args.spp))
        job = [j for j in full_jobs(lines) if j["job"] > before][-1]
        v.screenshot(os.path.join(out, "after.png"))
    finally:
        v.close()
    images = [(l["t"] - job["t"], l["samples"][0], l["image"]) for l in lines
              if "frame" in l and l.get("image") and l.get("canvas") == job["job"]]
    return job, args.spp, images


def load_image(path):
    w, h = (int(n) for n in re.search(r"-(\d+)x(\d+)\.f32$", path).groups())
    return np.fromfile(path, dtype="<f4").reshape(h, w, 3).astype(np.float64)


def with_sampler(scene, sampler, path):
    """A copy of `scene` rendered with `sampler` (`Stratified` or `Sobol`)."""
    with open(scene) as f:
        text = f.read()
    text = re.sub(r"\n\s*sampler:\s*\w+,", "", text)
    text, n = re.subn(r"(\n(\s*)samples_per_pixel:[^\n]*\n)", lambda m: f"{m.group(1)}{m.group(2)}sampler: {sampler},\n", text,
                      count=1)
    if n != 1:
        sys.exit(f"{scene}: no samples_per_pixel line to put the sampler after")
    base = os.path.dirname(os.path.abspath(scene))
    text = re.sub(r'(file:\s*)"([^"/][^"]*)"', lambda m: f'{m.group(1)}"{os.path.join(base, m.group(2))}"', text)
    with open(path, "w") as f:
        f.write(text)


def main():
    args = parse_args()
    mitsuba_compare.use_llvm19()
    os.makedirs(args.out, exist_ok=True)
    if args.sampler != "scene":
        copy = os.path.join(os.path.abspath(args.out), "scene-" + args.sampler + ".ron")
        with_sampler(args.scene, args.sampler.capitalize(), copy)
        args.scene = copy
    runs = [("plain", False)] + ([("denoised", True)] if args.denoise_at else [])
    results = {}
    for name, denoise in runs:
        print(f"viewer, {name}: first render, drag, render after the drag ...", flush=True)
        results[name] = measure(args, os.path.join(args.out, name), denoise)
    refs = {}
    for name, (job, _, _) in results.items():
        key = json.dumps(job["camera"], sort_keys=True)
        if key not in refs:
            width, height = job["size"]
            scene = os.path.join(os.path.abspath(args.out), f"moved-{len(refs)}.ron")
            scene_with_camera(args.scene, job["camera"], scene)
            print(f"reference of the {name} run's view: Mitsuba llvm_ad_rgb, {args.reference_spp} spp, "
                  f"{width}×{height} ...", flush=True)
            refs[key] = reference(args, scene, os.path.join(args.out, f"reference-{len(refs)}"), width, height)
    noise2 = max(n for _, n in refs.values())
    lines = [
        f"# Viewer: time from releasing the mouse to a clean image, {os.path.basename(args.scene)}",
        "",
        f"{width}×{height} (resolution scale {args.scale}), {args.threads} threads, release build; reference Mitsuba "
        f"llvm_ad_rgb {args.reference_spp} spp of each run's view (own RMSE up to {math.sqrt(noise2):.5f}, taken out); no visible grain: "
        f"RMSE ≤ {args.threshold}. Machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}.",
        "",
    ]
    summary = {}
    for name, (job, spp, images) in results.items():
        ref, noise2 = refs[json.dumps(job["camera"], sort_keys=True)]
        rows = []
        for t, n, path in images:
            im = load_image(path)
            e2 = float(np.mean((np.clip(im, 0, 1) - np.clip(ref, 0, 1)) ** 2)) - noise2
            rows.append((t, n, math.sqrt(max(e2, 1e-12))))
        lines += [f"## {name}", "", "| s after release | spp | RMSE |", "|---:|---:|---:|"]
        lines += [f"| {t:.3f} | {n} | {e:.5f} |" for t, n, e in rows]
        first = rows[0] if rows else None
        clean = next((r for r in rows if r[2] <= args.threshold), None)
        facts = {"first full image": first}
        if name == "denoised" and first:
            at_first = [r for r in rows if r[1] == first[1]]
            facts["denoised full image"] = at_first[-1]
        facts["no visible grain"] = clean
        summary[name] = facts
        lines.append("")
        for what, r in facts.items():
            lines.append(f"- {what}: " + (f"{r[0]:.2f} s ({r[1]} spp, RMSE {r[2]:.4f})" if r else
                                          f"not reached by {spp} spp"))
        lines.append("")
    report = "\n".join(lines) + "\n"
    print(report)
    with open(os.path.join(args.out, "report.md"), "w") as f:
        f.write(report)
    if not args.keep_images:
        for name in results:
            shutil.rmtree(os.path.join(args.out, name, "images"), ignore_errors=True)


if __name__ == "__main__":
    main()
