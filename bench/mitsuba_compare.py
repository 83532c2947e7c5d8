#!/usr/bin/env python3
"""rt-view beside Mitsuba 3 on the same scene: are the two images the same,
up to noise?

    pip install mitsuba numpy
    cargo build --release -p rt-view
    python3 bench/mitsuba_compare.py scenes/cornell_box.ron --spp 1024 --batches 8

The scene is exported by `rt-view export` (every default resolved, triangle
objects as OBJ files) and converted to a Mitsuba 3 scene:

- rt-view's world is left-handed, Mitsuba's right-handed: every position and
  direction has its x negated, and every triangle's winding is reversed, so
  that each surface keeps the side its normal points to. The camera is built
  with `look_at` from the mirrored eye, centre of interest and up vector.
- the camera is Mitsuba's `perspective` with the same vertical field of view,
  an `hdrfilm` of the same size with a box pixel filter (rt-view's samples are
  spread uniformly over each pixel), and the `independent` sampler;
- the integrator is `path` with `max_depth = max_bounces + 1` (Mitsuba counts
  the camera segment);
- a material is the mixture of `docs/effects.md`:
  `(1 − kr − kt)·[(1 − ks)·diffuse + ks·ggx] + kr·mirror + kt·glass`, built
  from nested `blendbsdf`s of `diffuse` (reflectance kd·color),
  `roughconductor` (GGX, α from the shininess, `material = "none"`),
  `conductor` (`material = "none"`) and `dielectric` (`int_ior = ior`,
  `specular_transmittance = color`). rt-view's reflection lobes are
  two-sided, so they are wrapped in `twosided`.
- an emissive object gets an `area` emitter of the same radiance (one-sided,
  on the side its normal points to, as in rt-view); the background becomes a
  `constant` emitter; an environment map becomes an `envmap` emitter of the
  same image with `scale` = strength and a rotation about +y by minus
  rt-view's (the x mirror turns rt-view's map convention into Mitsuba's; a
  map with a sun is refused); a thin lens becomes the `thinlens` sensor with
  the same `aperture_radius` and `focus_distance`; point and directional lights become `point` and
  `directional` emitters with the same intensity and irradiance.
- infinite planes become rectangles `--plane-size` units wide centred below
  the centre of interest (Mitsuba's rectangles are float32: a huge one makes
  its shading points drift).

Both renderers render `--batches` independent images of `--spp / --batches`
samples (rt-view with `--seed k`, Mitsuba with `seed=k`). For each 16×16
block of pixels the mean over each image is taken; the spread of the batch
means gives the standard error of a block's mean. A block agrees when, in
every colour channel,

    |rt − mi| ≤ Z·√(se_rt² + se_mi²) + rel·max(|rt|, |mi|)

(Z = `--z`, rel = `--rel`). Noise alone makes about 0.27 % of
channel tests fail at Z = 3. The whole-image means are compared too.
"""

import argparse
import contextlib
import json
import math
import os
import shutil
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common.images import block_means, block_z, srgb  # noqa: E402,F401  (srgb: also used by importers)


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene", help="rt-view scene file (.ron)")
    p.add_argument("--spp", type=int, default=1024, help="samples per pixel in all, each renderer")
    p.add_argument("--batches", type=int, default=16, help="independent images the samples are split into")
    p.add_argument("--variant", default="llvm_ad_rgb", help="Mitsuba variant (llvm_ad_rgb or scalar_rgb)")
    p.add_argument("--rt-view", default="target/release/rt-view", help="the rt-view binary")
    p.add_argument("--out", default="mitsuba-out", help="folder for images, exports and the report")
    p.add_argument("--threads", type=int, default=os.cpu_count(), help="threads for both renderers")
    p.add_argument("--block", type=int, default=16, help="block side in pixels")
    p.add_argument("--z", type=float, default=3.0, help="standard errors a block may differ by")
    p.add_argument("--rel", type=float, default=0.01, help="relative tolerance added to the noise bound")
    p.add_argument("--plane-size", type=float, default=400.0, help="width of the rectangle an infinite plane becomes")
    p.add_argument("--width", type=int, help="override the image width")
    p.add_argument("--height", type=int, help="override the image height")
    return p.parse_args()


def mirror(v):
    return [-v[0], v[1], v[2]]


def rgb(mi, c):
    return {"type": "rgb", "value": [float(x) for x in c]}


def mirrored_obj(src, dst):
    """Copies an OBJ of rt-view's export with x negated and windings reversed."""
    out = []
    with open(src) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                x, y, z = (float(t) for t in parts[1:4])
                out.append(f"v {-x!r} {y!r} {z!r}")
            elif parts[0] == "f":
                a, b, c = parts[1:4]
                out.append(f"f {a} {c} {b}")
    with open(dst, "w") as f:
        f.write("\n".join(out) + "\n")


def principled_bsdf(m):
    """Mitsuba's `principled` for a physically based rt-view material.

    Mitsuba's principled is Disney's 2015 BSDF, not glTF's; the two coincide
    for a metal (metallic 1: GGX with α = roughness², Schlick's Fresnel with
    f0 = base colour) except for the masking-shadowing term (Mitsuba:
    separable Smith G₁·G₁, rt-view: height-correlated), and differ for a
    dielectric (Disney's retro-reflective diffuse, its own Fresnel mix) and
    in the clearcoat (Disney's GTR1 of fixed strength). See docs/models.md.
    """
    p = m["physical"]
    bsdf = {
        "type": "principled",
        "base_color": {"type": "rgb", "value": m["color"]},
        "metallic": p["metallic"],
        "roughness": p["roughness"],
        "spec_tint": 0.0,
        "spec_trans": p["transmission"],
        "eta": max(m["ior"], 1.0001),
        "clearcoat": p["clearcoat"],
        "clearcoat_gloss": 1.0 - p["clearcoat_roughness"],
    }
    return bsdf if p["transmission"] > 0 else {"type": "twosided", "bsdf": bsdf}


def bsdf(m):
    """The Mitsuba BSDF of an rt-view material (see the module comment)."""
    if m.get("physical"):
        return principled_bsdf(m)
    kr, kt, ks, kd = m["reflectivity"], m["transparency"], m["specular"], m["diffuse"]
    color = m["color"]
    tint = m.get("specular_color", [1.0, 1.0, 1.0])  # the glossy and mirror lobes' tint
    rest_black = kd * max(color) <= 0 and ks <= 0
    delta = kr + kt
    if delta > 0:
        # The δ lobes, each scaled by the sum of their weights so that a
        # blend of the two gives kr·mirror + kt·glass.
        mirror_bsdf = {
            "type": "twosided",
            "bsdf": {
                "type": "conductor",
                "material": "none",
                "specular_reflectance": {"type": "rgb", "value": [delta * t for t in tint]},
            },
        }
        glass = {
            "type": "dielectric",
            "int_ior": m["ior"],
            "ext_ior": 1.0,
            "specular_reflectance": {"type": "rgb", "value": [delta] * 3},
            "specular_transmittance": {"type": "rgb", "value": [delta * c for c in color]},
        }
        if kt <= 0:
            deltas = mirror_bsdf
        elif kr <= 0:
            deltas = glass
        else:
            deltas = {"type": "blendbsdf", "weight": kt / delta, "bsdf_0": mirror_bsdf, "bsdf_1": glass}
        if rest_black or delta >= 1:
            return deltas
        # Mitsuba's blendbsdf divides a δ sample's weight by the mixture's
        # density, in which the smooth lobe's density is added to the δ lobe's
        # selection probability: the δ lobe comes out darker than its weight.
        print(
            f"warning: material {m['name']!r} mixes smooth and δ lobes, which Mitsuba's blendbsdf "
            "does not weight exactly: the reference is biased where it is seen",
            file=sys.stderr,
        )
    diffuse = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [kd * c for c in color]}}
    glossy = {
        "type": "roughconductor",
        "distribution": "ggx",
        "alpha": m["roughness"],
        "material": "none",
        "specular_reflectance": {"type": "rgb", "value": tint},
    }
    if ks <= 0:
        rest = diffuse
    elif ks >= 1:
        rest = glossy
    else:
        rest = {"type": "blendbsdf", "weight": ks, "bsdf_0": diffuse, "bsdf_1": glossy}
    rest = {"type": "twosided", "bsdf": rest}
    if delta <= 0:
        return rest
    # The δ lobes were scaled by kr + kt; the blend's weight kr + kt scales
    # them once more: undo it.
    for part in [deltas] + ([deltas["bsdf_0"], deltas["bsdf_1"]] if deltas["type"] == "blendbsdf" else []):
        inner = part.get("bsdf", part)
        for key in ("specular_reflectance", "specular_transmittance"):
            if key in inner:
                inner[key]["value"] = [v / delta for v in inner[key]["value"]]
    return {"type": "blendbsdf", "weight": delta, "bsdf_0": rest, "bsdf_1": deltas}


def chromatic(desc):
    """Whether some medium's mean free path differs between channels."""
    return any(
        m.get("subsurface") and len(set(m["subsurface"]["mean_free_path"])) > 1 for m in desc["materials"]
    )


def one_channel(desc, channel):
    """The export with every medium's mean free path set to that of `channel`
    in all three channels (albedo and the rest unchanged)."""
    out = json.loads(json.dumps(desc))
    for m in out["materials"]:
        if m.get("subsurface"):
            m["subsurface"]["mean_free_path"] = [m["subsurface"]["mean_free_path"][channel]] * 3
    return out


def mitsuba_scene(mi, desc, folder, width, height, plane_size):
    """The Mitsuba scene dictionary of an rt-view export."""
    T = mi.ScalarTransform4f
    cam = desc["camera"]
    if cam["projection"] != "Perspective":
        sys.exit("only perspective cameras are converted")
    gi = desc["global_illumination"]
    if gi is None:
        sys.exit("the scene has no global_illumination: nothing to compare with a path tracer")
    materials = {m["name"]: m for m in desc["materials"]}
    translucent = any(m.get("subsurface") for m in materials.values())
    if translucent:
        # Media need the volumetric path tracer. Its depth counts scattering
        # events inside media as well as surfaces, which rt-view's
        # max_bounces does not (a walk is capped by max_walk_steps instead):
        # the reference runs without a depth limit, so the scene's
        # max_bounces must be high enough not to matter.
        if gi["max_bounces"] < 32:
            print(f"warning: max_bounces {gi['max_bounces']} truncates rt-view's paths; Mitsuba's volpath "
                  "runs without a limit here", file=sys.stderr)
        integrator = {"type": "volpath", "max_depth": -1, "hide_emitters": False}
    else:
        integrator = {"type": "path", "max_depth": gi["max_bounces"] + 1, "hide_emitters": False}
    scene = {
        "type": "scene",
        "integrator": integrator,
        "sensor": {
            "type": "perspective",
            "fov": cam["fov_y"],
            "fov_axis": "y",
            "near_clip": 1e-3,
            "to_world": T().look_at(
                origin=mirror(cam["position"]), target=mirror(cam["center_of_interest"]), up=mirror(cam["up"])
            ),
            "film": {
                "type": "hdrfilm",
                "width": width,
                "height": height,
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
            "sampler": {"type": "independent", "sample_count": 1},
        },
    }
    if max(desc["background"]) > 0:
        scene["background"] = {"type": "constant", "radiance": rgb(mi, desc["background"])}
    environment = desc.get("environment")
    if environment:
        if environment.get("sun"):
            sys.exit("the environment has a sun disc, which Mitsuba's envmap cannot hold (its sunsky is another model)")
        # rt-view's map convention is Mitsuba's envmap after the x mirror;
        # rt-view's rotation ρ about +y is Mitsuba's rotation by −ρ.
        scene["environment"] = {
            "type": "envmap",
            "filename": os.path.join(folder, environment["file"]),
            "scale": environment["strength"],
            "to_world": T().rotate([0, 1, 0], -environment["rotation_degrees"]),
        }
    if cam.get("aperture", 0) > 0:
        # The same thin lens: Mitsuba's aperture_radius and focus_distance
        # (from the lens along the view direction) are rt-view's.
        scene["sensor"]["type"] = "thinlens"
        scene["sensor"]["aperture_radius"] = cam["aperture"]
        scene["sensor"]["focus_distance"] = cam["focus_distance"]
    coi = np.array(cam["center_of_interest"])
    unexported = [m["name"] for m in desc["materials"] if m.get("textured")]
    unexported += [f"object {i}" for i, o in enumerate(desc["objects"]) if o.get("smooth")]
    if unexported:
        sys.exit(
            "the export carries neither textures nor vertex normals, so Mitsuba would render another "
            f"scene: {', '.join(unexported)}"
        )
    for i, o in enumerate(desc["objects"]):
        m = materials[o["material"]]
        if o["kind"] == "Sphere":
            shape = {"type": "sphere", "center": mirror(o["center"]), "radius": o["radius"]}
        elif o["kind"] == "Plane":
            n = np.array(o["normal"])
            centre = coi - (coi.dot(n) - o["d"]) * n
            helper = [0.0, 0.0, 1.0] if abs(n[1]) > 0.9 or abs(n[0]) > 0.9 else [0.0, 1.0, 0.0]
            to_world = T().look_at(
                origin=mirror(centre.tolist()), target=mirror((centre + n).tolist()), up=mirror(helper)
            ) @ T().scale([plane_size / 2, plane_size / 2, 1])
            shape = {"type": "rectangle", "to_world": to_world}
        else:
            path = os.path.join(folder, f"mitsuba-{i}.obj")
            mirrored_obj(os.path.join(folder, o["file"]), path)
            shape = {"type": "obj", "filename": path, "face_normals": True}
        shape["bsdf"] = bsdf(m)
        medium = m.get("subsurface")
        if medium:
            # A smooth dielectric (or, at ior 1, index-matched: null) boundary
            # around a homogeneous medium; σt = 1/mean free path. The mirrored
            # OBJ keeps the faces wound outward, so the interior is inside.
            if m["ior"] == 1.0:
                shape["bsdf"] = {"type": "null"}
            else:
                shape["bsdf"] = {"type": "dielectric", "int_ior": m["ior"], "ext_ior": 1.0}
            # Mitsuba reads an RGB sigma_t as a reflectance in [0, 1]: give
            # it relative to the largest channel, times `scale`.
            sigma_t = [1.0 / l for l in medium["mean_free_path"]]
            shape["interior"] = {
                "type": "homogeneous",
                "albedo": rgb(mi, medium["albedo"]),
                "sigma_t": rgb(mi, [s / max(sigma_t) for s in sigma_t]),
                "scale": max(sigma_t),
                "phase": {"type": "hg", "g": medium["anisotropy"]},
            }
        if max(m["emission"]) > 0:
            shape["emitter"] = {"type": "area", "radiance": rgb(mi, m["emission"])}
        scene[f"object-{i}"] = shape
    for i, light in enumerate(desc["lights"]):
        if not light["shadows"]:
            sys.exit(f"lights[{i}] has shadows: false, which Mitsuba cannot render")
        if light["kind"] == "Point":
            scene[f"light-{i}"] = {"type": "point", "position": mirror(light["position"]), "intensity": rgb(mi, light["power"])}
        elif light["kind"] == "Directional":
            scene[f"light-{i}"] = {
                "type": "directional",
                "direction": mirror(light["direction"]),
                "irradiance": rgb(mi, light["power"]),
            }
        else:
            sys.exit(f"lights[{i}] is a sphere light, invisible to rays in rt-view: no Mitsuba equivalent")
    return scene


def use_llvm19():
    """Points Dr.Jit at Debian's LLVM 19 unless told otherwise: older LLVMs
    fail on the `path` integrator's kernels."""
    llvm = "/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1"
    if "DRJIT_LIBLLVM_PATH" not in os.environ and os.path.exists(llvm):
        os.environ["DRJIT_LIBLLVM_PATH"] = llvm


def set_llvm_lanes(dr, mi, lanes):
    """Makes Dr.Jit's LLVM backend compile `lanes`-wide kernels from now on.

    By default it compiles for the host CPU at its widest vectors: on a CPU
    with AVX-512, 16 lanes (`<16 x float>` in the kernels that
    `dr.set_log_level(dr.LogLevel.Trace)` prints), and Mitsuba then hands its
    rays to Embree 16 at a time. With `lanes` = 8 the AVX-512 features are
    switched off (the host CPU otherwise) and kernels and ray packets are
    8 wide, as AVX2 has them. Dr.Jit's Python module does not expose the
    setting, so this calls its C++ library (`jit_llvm_set_target`) through
    ctypes. Call it after `mi.set_variant` of an `llvm_` variant."""
    import ctypes
    lib = _drjit_core(dr)
    cpu = ctypes.CFUNCTYPE(ctypes.c_char_p)(("_Z19jit_llvm_target_cpuv", lib))
    features = ctypes.CFUNCTYPE(ctypes.c_char_p)(("_Z24jit_llvm_target_featuresv", lib))
    set_target = ctypes.CFUNCTYPE(None, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_uint32)(
        ("_Z19jit_llvm_set_targetPKcS0_j", lib))
    dr.eval(dr.arange(mi.Float, 1))  # starts the backend, which sets the host's target
    if lanes == llvm_lanes(dr):
        return
    if lanes != 8:
        raise SystemExit(f"--llvm-lanes: only 8 (AVX2) can be chosen, not {lanes}")
    wide = ("+avx512", "+evex512")
    narrowed = ",".join("-" + f[1:] if f.startswith(wide) else f for f in features().decode().split(","))
    set_target(cpu(), narrowed.encode(), 8)
    if llvm_lanes(dr) != 8:
        raise SystemExit("Dr.Jit did not take the 8-lane target")


def _drjit_core(dr):
    """Dr.Jit's C++ library, for the settings its Python module leaves out."""
    import ctypes
    return ctypes.CDLL(os.path.join(os.path.dirname(dr.__file__), "libdrjit-core.so"))


def llvm_lanes(dr):
    """How many lanes wide Dr.Jit's LLVM backend compiles kernels now."""
    import ctypes
    return ctypes.CFUNCTYPE(ctypes.c_uint32)(("_Z21jit_llvm_vector_widthv", _drjit_core(dr)))()


def export_scene(rt_view, scene, folder):
    """Empties `folder` and exports `scene` into it with `rt-view export`;
    returns the scene's description."""
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    export = os.path.join(folder, "scene.json")
    subprocess.run([rt_view, "export", scene, "-o", export], check=True)
    with open(export) as f:
        return json.load(f)


@contextlib.contextmanager
def bitmap_io():
    """Runs Mitsuba's image reading and writing (`mi.Bitmap`) with at least
    two threads in Dr.Jit's pool, and sets the pool back after: with one
    thread (`--threads 1`), reading or writing an EXR file never returns
    (Mitsuba 3.9.1, Dr.Jit 1.5.0)."""
    import drjit as dr
    threads = dr.thread_count()
    if threads < 2:
        dr.set_thread_count(2)
    try:
        yield
    finally:
        if threads < 2:
            dr.set_thread_count(threads)


def read_exr(mi, path):
    with bitmap_io():
        return np.array(mi.Bitmap(path), dtype=np.float64)[:, :, :3]


def main():
    args = parse_args()
    import drjit as dr
    import mitsuba as mi

    use_llvm19()
    mi.set_variant(args.variant)
    dr.set_thread_count(args.threads)

    name = os.path.splitext(os.path.basename(args.scene))[0]
    folder = os.path.join(args.out, name)
    desc = export_scene(args.rt_view, args.scene, folder)
    width = args.width or desc["width"]
    height = args.height or desc["height"]
    per_batch = max(1, args.spp // args.batches)
    # Mitsuba's volpath draws a free path from one channel chosen per path
    # and weighs the others by that channel's density alone (no MIS over the
    # channels): where mean free paths differ between channels its estimates
    # of the others have rare, huge weights and converge far too slowly to
    # serve as a reference. The channels of such a scene do not interact, so
    # each is rendered on its own with grey media of that channel's mean free
    # path, and the three are put together.
    split = chromatic(desc)
    if split:
        print("chromatic media: Mitsuba renders each channel with grey media (3 renders per batch)", file=sys.stderr)
        scenes = [
            mi.load_dict(mitsuba_scene(mi, one_channel(desc, c), folder, width, height, args.plane_size))
            for c in range(3)
        ]
    else:
        scene = mi.load_dict(mitsuba_scene(mi, desc, folder, width, height, args.plane_size))

    env = dict(os.environ, RAYON_NUM_THREADS=str(args.threads))
    rt_images, mi_images = [], []
    rt_time = mi_time = 0.0
    for k in range(args.batches):
        out = os.path.join(folder, f"rt-{k}.exr")
        command = [args.rt_view, "render", args.scene, "-o", out, "--spp", str(per_batch), "--seed", str(k)]
        command += ["--width", str(width), "--height", str(height)]
        start = time.perf_counter()
        subprocess.run(command, check=True, env=env, stderr=subprocess.DEVNULL)
        rt_time += time.perf_counter() - start
        rt_images.append(read_exr(mi, out))
        start = time.perf_counter()
        if split:
            pixels = np.stack(
                [np.array(mi.render(scenes[c], spp=per_batch, seed=k), dtype=np.float64)[:, :, c] for c in range(3)],
                axis=2,
            )
        else:
            image = mi.render(scene, spp=per_batch, seed=k)
            pixels = np.array(image, dtype=np.float64)[:, :, :3]
        mi_time += time.perf_counter() - start
        mi_images.append(pixels)
        print(f"batch {k + 1}/{args.batches}: rt-view {rt_time:.1f} s, Mitsuba {mi_time:.1f} s so far", flush=True)

    rt_blocks = np.stack([block_means(im, args.block) for im in rt_images])
    mi_blocks = np.stack([block_means(im, args.block) for im in mi_images])
    n = args.batches
    rt_mean, mi_mean = rt_blocks.mean(0), mi_blocks.mean(0)
    rt_se = rt_blocks.std(0, ddof=1) / math.sqrt(n)
    mi_se = mi_blocks.std(0, ddof=1) / math.sqrt(n)
    bound = args.z * np.sqrt(rt_se**2 + mi_se**2) + args.rel * np.maximum(np.abs(rt_mean), np.abs(mi_mean))
    agree_channel = np.abs(rt_mean - mi_mean) <= bound
    agree = agree_channel.all(axis=2)
    fraction = agree.mean()

    rt_image = np.mean(rt_images, axis=0)
    mi_image = np.mean(mi_images, axis=0)
    rt_total, mi_total = rt_image.mean(axis=(0, 1)), mi_image.mean(axis=(0, 1))
    ratio = rt_total / np.maximum(mi_total, 1e-30)
    rt_total_se = np.array([im.mean(axis=(0, 1)) for im in rt_images]).std(0, ddof=1) / math.sqrt(n)
    mi_total_se = np.array([im.mean(axis=(0, 1)) for im in mi_images]).std(0, ddof=1) / math.sqrt(n)
    total_z = (rt_total - mi_total) / np.maximum(np.sqrt(rt_total_se**2 + mi_total_se**2), 1e-30)
    z_scores, z_line = block_z(rt_mean, rt_se, mi_mean, mi_se)

    lines = [
        f"# {name}: rt-view against Mitsuba 3 ({args.variant})",
        "",
        f"- {width}×{height}, {per_batch * n} samples per pixel each, in {n} independent batches;"
        f" {args.threads} threads",
        f"- blocks of {args.block}×{args.block}: {agree.sum()} of {agree.size} agree"
        f" ({100 * fraction:.1f} %) within {args.z} standard errors + {100 * args.rel:g} %",
        f"- {z_line}",
        f"- whole-image mean, rt-view / Mitsuba: R {ratio[0]:.4f}, G {ratio[1]:.4f}, B {ratio[2]:.4f}"
        f" (rt-view {rt_total.round(5).tolist()}, Mitsuba {mi_total.round(5).tolist()};"
        f" z {total_z.round(1).tolist()})",
        f"- render time: rt-view {rt_time:.2f} s, Mitsuba {mi_time:.2f} s",
    ]
    passed = fraction >= 0.99 and np.all(np.abs(ratio - 1) <= 0.01)
    worst = np.argsort(-np.abs(z_scores).max(axis=2), axis=None)[:5]
    for index in worst:
        by, bx = np.unravel_index(index, agree.shape)
        lines.append(
            f"  - block ({bx}, {by}): rt-view {rt_mean[by, bx].round(4).tolist()} ± {rt_se[by, bx].round(4).tolist()},"
            f" Mitsuba {mi_mean[by, bx].round(4).tolist()} ± {mi_se[by, bx].round(4).tolist()}"
        )
    lines.append(f"- verdict: {'AGREE' if passed else 'DIFFER'} (needs ≥ 99 % of blocks and image means within 1 %)")
    report = "\n".join(lines) + "\n"
    print(report)
    with open(os.path.join(folder, "report.md"), "w") as f:
        f.write(report)

    # Pictures: rt-view | Mitsuba | blocks that disagree (red).
    side = np.concatenate([srgb(rt_image), srgb(mi_image)], axis=1)
    marks = srgb(mi_image).copy()
    for by, bx in zip(*np.nonzero(~agree)):
        y0, x0 = by * args.block, bx * args.block
        marks[y0 : y0 + args.block, x0 : x0 + args.block] = (marks[y0 : y0 + args.block, x0 : x0 + args.block] // 2) + [
            127,
            0,
            0,
        ]
    # The signed z-score of each block's luminance: red where rt-view is
    # brighter, blue where Mitsuba is, full colour at 5 standard errors.
    zl = z_scores.mean(axis=2)
    heat = np.zeros(zl.shape + (3,), dtype=np.uint8)
    heat[..., 0] = np.clip(zl / 5, 0, 1) * 255
    heat[..., 2] = np.clip(-zl / 5, 0, 1) * 255
    heat = np.kron(heat, np.ones((args.block, args.block, 1), dtype=np.uint8))
    full = np.zeros_like(marks)
    full[: heat.shape[0], : heat.shape[1]] = heat
    picture = np.concatenate([side, marks, full], axis=1)
    with bitmap_io():
        mi.Bitmap(picture).write(os.path.join(folder, "compare.png"))
        mi.Bitmap(rt_image.astype(np.float32)).write(os.path.join(folder, "rt-view.exr"))
        mi.Bitmap(mi_image.astype(np.float32)).write(os.path.join(folder, "mitsuba.exr"))
    sys.exit(0 if passed else 1)


if __name__ == "__main__":
    main()
