#!/usr/bin/env python3
"""rt-view beside Blender Cycles on the same glTF scene: are the two images
the same, up to noise?

    python3.11 -m venv venv-bpy && venv-bpy/bin/pip install bpy==5.0.1 numpy
    cargo build --release -p rt-view
    venv-bpy/bin/python bench/cycles_compare.py scenes/cycles_spheres.ron --spp 256 --batches 8

The scene must be of the form of `scenes/cycles_*.ron` (written for
`scripts/make_blender_scenes.py`'s models): one `Mesh` of a `.glb` with
`lights: true`, the camera taken from the same file (`camera: (gltf: …)`),
a constant `background` and global illumination. Cycles renders the same
`.glb`, read by Blender's own glTF importer:

- lights in glTF's photometric units ("Standard" lighting mode of the
  importer, `export_import_convert_lighting_mode = 'SPEC'`, the mode the
  exporter wrote them in): a point light's candela I becomes 4π·I/683 W,
  which Cycles spreads as I/683 W/sr, a sun's lux E becomes E/683 W/m²;
  rt-view divides by 683 lm/W the same way (docs/models.md). The importer
  gives every sun Blender's default disc of 0.526°, which is set to 0, and
  a point light any radius it has is set to 0 too (punctual, as in glTF and
  rt-view); each change is printed.
- the camera is the file's (`yfov`, vertical sensor fit), the image the
  same size; Cycles' pixel filter is a box of 1 pixel (rt-view's samples are
  spread uniformly over each pixel); no denoising, no adaptive sampling, no
  clamping, no filter-glossy, reflective and refractive caustics on, no
  light-sampling threshold, no path guiding; the light tree is left on
  (it changes the noise, not the expectation).
- bounces: rt-view's `max_bounces` N (1 is direct lighting) is Cycles'
  N − 1 (0 is direct lighting), for every kind of bounce; both use Russian
  roulette.
- the world is a uniform background of the scene's `background` colour,
  strength 1 (it lights the scene in both).
- every Principled BSDF's microfacet distribution is set to single-scattering
  `GGX` (the importer leaves Cycles' default, `MULTI_GGX`, which adds the
  light the single-scattering model loses); `--multiscatter` keeps it.
- the output is linear OpenEXR (scene-linear Rec.709, which is rt-view's
  linear sRGB), with the Standard view transform (not used by EXR anyway).

What still differs between the two models, by design, is listed in
docs/models.md ("Compared with Blender Cycles"): Cycles' Fresnel for an
opaque dielectric is exact, not Schlick's (rt-view's glass uses the exact
one too); its diffuse base is scaled by the specular layer's tabulated
albedo at the view, where rt-view's reciprocal weighting also takes it at
the light; rt-view mip-maps normal maps, Cycles reads them full-size; a metal's edge uses the F82-tint model; Cycles offsets
shadow rays of smooth meshes (its shadow-terminator geometry offset, 0.1),
where rt-view uses Chiang et al.'s terminator term.

Both renderers render `--batches` independent images of `--spp / --batches`
samples (rt-view with `--seed k`, Cycles with `seed = k`). For each 16×16
block of pixels the mean over each image is taken; the spread of the batch
means gives the standard error of a block's mean. A block agrees when, in
every colour channel,

    |rt − cy| ≤ Z·√(se_rt² + se_cy²) + rel·max(|rt|, |cy|)

(Z = `--z`, rel = `--rel`), as bench/mitsuba_compare.py does. The
whole-image means are compared too, and the mean over a disc of 0.7 of
the projected bounding sphere of every object not named `floor` or `wall`
(the spheres of the grid, the glass, Suzanne).

With `--mitsuba` (the `mitsuba` package installed beside `bpy`), Mitsuba 3
renders the scene Blender imported, as a third opinion: every mesh written
as an OBJ file with its vertex normals in Blender's world frame (right-
handed, as Mitsuba's; nothing is mirrored), the camera, point lights
(intensity = watts/4π) and suns (`directional`, irradiance = strength), the
background as a `constant` emitter, the `path` integrator with
`max_depth = max_bounces + 1`. A Principled BSDF becomes a `roughdielectric`
(GGX, α = roughness², its IOR, the base colour as transmittance) when its
transmission is 1, a two-sided `diffuse` of the base colour when it has no
specular reflection and no metal (specular IOR level 0, metallic 0), and
Mitsuba's `principled` (Disney 2015, another model: see docs/models.md)
otherwise; a textured material is refused.
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
from common import cycles  # noqa: E402
from common.cycles import read_exr, write_png  # noqa: E402
from common.images import agreement, block_means, block_z, srgb  # noqa: E402


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene", help="rt-view scene file (.ron) of the scenes/cycles_*.ron form")
    p.add_argument("--spp", type=int, default=256, help="samples per pixel in all, each renderer")
    p.add_argument("--batches", type=int, default=8, help="independent images the samples are split into")
    p.add_argument("--rt-view", default="target/release/rt-view", help="the rt-view binary")
    p.add_argument("--out", default="cycles-out", help="folder for images and the report")
    p.add_argument("--threads", type=int, default=os.cpu_count(), help="threads for both renderers")
    p.add_argument("--block", type=int, default=16, help="block side in pixels")
    p.add_argument("--z", type=float, default=3.0, help="standard errors a block may differ by")
    p.add_argument("--rel", type=float, default=0.01, help="relative tolerance added to the noise bound")
    p.add_argument("--width", type=int, help="override the image width")
    p.add_argument("--height", type=int, help="override the image height")
    p.add_argument("--multiscatter", action="store_true", help="keep Cycles' multiple-scattering GGX")
    p.add_argument("--mitsuba", action="store_true", help="render a third image with Mitsuba 3 (pip install mitsuba)")
    p.add_argument("--variant", default="scalar_rgb", help="Mitsuba variant, with --mitsuba")
    return p.parse_args()


def scene_facts(rt_view, scene, folder):
    """The .glb, image size, background and bounces of an rt-view scene of
    the cycles_*.ron form (the .ron read for the file, `rt-view export` for
    every resolved default)."""
    with open(scene) as f:
        text = f.read()
    meshes = re.findall(r'Mesh\(\s*file:\s*"([^"]+\.glb)"', text)
    cameras = re.findall(r'camera:\s*\(\s*gltf:\s*"([^"]+)"', text)
    if len(meshes) != 1 or cameras != meshes or not re.search(r"lights:\s*true", text):
        sys.exit(
            f"{scene}: needs exactly one Mesh of a .glb with `lights: true` and `camera: (gltf: …)` of the same file"
        )
    glb = os.path.normpath(os.path.join(os.path.dirname(scene), meshes[0]))
    os.makedirs(folder, exist_ok=True)
    export = os.path.join(folder, "scene.json")
    subprocess.run([rt_view, "export", scene, "-o", export], check=True, stderr=subprocess.DEVNULL)
    with open(export) as f:
        desc = json.load(f)
    gi = desc.get("global_illumination")
    if gi is None:
        sys.exit(f"{scene}: has no global_illumination: nothing to compare with a path tracer")
    if desc.get("environment"):
        sys.exit(f"{scene}: an environment map is not converted; use a constant background")
    return glb, desc


def cycles_scene(bpy, glb, desc, width, height, threads, multiscatter):
    """Blender's scene for `glb`, set up as the module comment says; returns
    what was changed on import, a line each."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=os.path.abspath(glb), export_import_convert_lighting_mode="SPEC")
    scene = bpy.context.scene
    cameras = [o for o in scene.objects if o.type == "CAMERA"]
    if not cameras:
        sys.exit(f"{glb}: has no camera")
    scene.camera = cameras[0]
    notes = []
    for obj in scene.objects:
        if obj.type == "LIGHT":
            light = obj.data
            if light.type in ("POINT", "SPOT") and light.shadow_soft_size != 0:
                notes.append(f"light {obj.name!r}: radius {light.shadow_soft_size:g} → 0")
                light.shadow_soft_size = 0.0
            if light.type == "SUN" and light.angle != 0:
                notes.append(f"sun {obj.name!r}: angle {math.degrees(light.angle):.3g}° → 0")
                light.angle = 0.0
    for mat in bpy.data.materials:
        if not mat.node_tree:
            continue
        for node in mat.node_tree.nodes:
            if node.type == "BSDF_PRINCIPLED" and not multiscatter and node.distribution != "GGX":
                node.distribution = "GGX"
                notes.append(f"material {mat.name!r}: distribution MULTI_GGX → GGX")
    scene.world = cycles.uniform_world(bpy, desc["background"])
    cycles.settings(scene, width, height, threads, desc["global_illumination"]["max_bounces"] - 1)
    return scene, notes


def mitsuba_bsdf(mat):
    """The Mitsuba BSDF of a Blender material (see the module comment)."""
    nodes = [n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED"] if mat and mat.node_tree else []
    if len(nodes) != 1:
        sys.exit(f"material {mat.name if mat else None!r}: not one Principled BSDF")
    inputs = nodes[0].inputs
    linked = [i.name for i in inputs if i.is_linked]
    if linked:
        sys.exit(f"material {mat.name!r}: driven by textures or nodes ({', '.join(linked)}): not converted for Mitsuba")
    value = lambda name: inputs[name].default_value  # noqa: E731
    base = [float(c) for c in value("Base Color")[:3]]
    roughness, metallic, ior = float(value("Roughness")), float(value("Metallic")), float(value("IOR"))
    if value("Transmission Weight") >= 1 and metallic == 0:
        if roughness**2 < 1e-3:
            return {"type": "dielectric", "int_ior": ior, "ext_ior": 1.0}
        return {
            "type": "roughdielectric",
            "distribution": "ggx",
            "alpha": roughness**2,
            "int_ior": ior,
            "ext_ior": 1.0,
            "specular_transmittance": {"type": "rgb", "value": base},
        }
    if value("Specular IOR Level") == 0 and metallic == 0 and value("Transmission Weight") == 0:
        return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {"type": "rgb", "value": base}}}
    return {
        "type": "twosided",
        "bsdf": {
            "type": "principled",
            "base_color": {"type": "rgb", "value": base},
            "metallic": metallic,
            "roughness": roughness,
            "spec_tint": 0.0,
            "eta": max(ior, 1.0001),
        },
    }


def mitsuba_scene(mi, bpy, scene, desc, folder, width, height):
    """The Mitsuba scene dictionary of the scene Blender imported."""
    from mathutils import Vector

    T = mi.ScalarTransform4f
    cam = scene.camera
    rot = cam.matrix_world.to_3x3()
    eye = cam.matrix_world.translation
    out = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": desc["global_illumination"]["max_bounces"] + 1},
        "sensor": {
            "type": "perspective",
            "fov": math.degrees(cam.data.angle_y),
            "fov_axis": "y",
            "near_clip": 1e-3,
            "to_world": T().look_at(
                origin=list(eye), target=list(eye + rot @ Vector((0, 0, -1))), up=list(rot @ Vector((0, 1, 0)))
            ),
            "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"}},
            "sampler": {"type": "independent", "sample_count": 1},
        },
        "background": {"type": "constant", "radiance": {"type": "rgb", "value": list(desc["background"])}},
    }
    depsgraph = bpy.context.evaluated_depsgraph_get()
    for i, obj in enumerate(scene.objects):
        if obj.type == "MESH":
            mesh = obj.evaluated_get(depsgraph).to_mesh()
            mesh.calc_loop_triangles()
            normal_matrix = obj.matrix_world.to_3x3().inverted().transposed()
            path = os.path.join(folder, f"mitsuba-{i}.obj")
            with open(path, "w") as f:
                for v in mesh.vertices:
                    p = obj.matrix_world @ v.co
                    n = (normal_matrix @ v.normal).normalized()
                    f.write(f"v {p.x!r} {p.y!r} {p.z!r}\nvn {n.x!r} {n.y!r} {n.z!r}\n")
                for t in mesh.loop_triangles:
                    a, b, c = (j + 1 for j in t.vertices)
                    f.write(f"f {a}//{a} {b}//{b} {c}//{c}\n")
            out[f"mesh-{i}"] = {"type": "obj", "filename": path, "bsdf": mitsuba_bsdf(obj.active_material)}
        elif obj.type == "LIGHT":
            light = obj.data
            color = [float(c) for c in light.color]
            if light.type == "POINT":
                power = [light.energy / (4 * math.pi) * c for c in color]
                position = list(obj.matrix_world.translation)
                out[f"light-{i}"] = {"type": "point", "position": position, "intensity": {"type": "rgb", "value": power}}
            elif light.type == "SUN":
                direction = list(obj.matrix_world.to_3x3() @ Vector((0, 0, -1)))
                irradiance = {"type": "rgb", "value": [light.energy * c for c in color]}
                out[f"light-{i}"] = {"type": "directional", "direction": direction, "irradiance": irradiance}
            else:
                sys.exit(f"light {obj.name!r}: a {light.type} light is not converted for Mitsuba")
    return out


def disc_ratio(a, b, cx, cy, r):
    """Mean luminance over a disc, a/b, and two standard errors of it."""
    lum = np.array([0.2126, 0.7152, 0.0722])
    la = np.array([disc_mean(im, cx, cy, r) @ lum for im in a])
    lb = np.array([disc_mean(im, cx, cy, r) @ lum for im in b])
    q = la.mean() / max(lb.mean(), 1e-30)
    n = len(a)
    se = q * math.sqrt((la.std(ddof=1) / la.mean()) ** 2 / n + (lb.std(ddof=1) / lb.mean()) ** 2 / n)
    return q, 2 * se


def object_discs(bpy, scene, width, height):
    """(name, centre x, centre y, radius) in pixels of a disc of 0.7 of the
    projected bounding sphere of each mesh object not named floor or wall."""
    from bpy_extras.object_utils import world_to_camera_view
    from mathutils import Vector

    cam = scene.camera
    tan_half = math.tan(cam.data.angle_y / 2)
    discs = []
    for obj in scene.objects:
        if obj.type != "MESH" or any(word in obj.name.lower() for word in ("floor", "wall")):
            continue
        corners = [obj.matrix_world @ Vector(c) for c in obj.bound_box]
        centre = sum(corners, Vector()) / 8
        radius = max((c - centre).length for c in corners) / math.sqrt(3)
        ndc = world_to_camera_view(scene, cam, centre)
        if ndc.z <= 0:
            continue
        r_px = 0.7 * radius / (ndc.z * tan_half) * height / 2
        discs.append((obj.name, ndc.x * width, (1 - ndc.y) * height, r_px))
    return sorted(discs, key=lambda d: (round(d[2] / 8), round(d[1] / 8)))


def disc_mean(image, cx, cy, r):
    h, w, _ = image.shape
    y, x = np.mgrid[0:h, 0:w] + 0.5
    mask = (x - cx) ** 2 + (y - cy) ** 2 <= r * r
    return image[mask].mean(axis=0) if mask.any() else None


def main():
    args = parse_args()
    import bpy

    name = os.path.splitext(os.path.basename(args.scene))[0]
    folder = os.path.join(args.out, name)
    shutil.rmtree(folder, ignore_errors=True)
    glb, desc = scene_facts(args.rt_view, args.scene, folder)
    width = args.width or desc["width"]
    height = args.height or desc["height"]
    per_batch = max(1, args.spp // args.batches)
    scene, notes = cycles_scene(bpy, glb, desc, width, height, args.threads, args.multiscatter)
    for note in notes:
        print(f"cycles: {note}")

    mi_scene = None
    if args.mitsuba:
        import drjit as dr
        import mitsuba as mi

        mi.set_variant(args.variant)
        dr.set_thread_count(args.threads)
        mi_scene = mi.load_dict(mitsuba_scene(mi, bpy, scene, desc, folder, width, height))

    env = dict(os.environ, RAYON_NUM_THREADS=str(args.threads))
    rt_images, cy_images, mi_images = [], [], []
    rt_time = cy_time = mi_time = 0.0
    for k in range(args.batches):
        out = os.path.join(folder, f"rt-{k}.exr")
        command = [args.rt_view, "render", args.scene, "-o", out, "--spp", str(per_batch), "--seed", str(k)]
        command += ["--width", str(width), "--height", str(height)]
        start = time.perf_counter()
        subprocess.run(command, check=True, env=env, stderr=subprocess.DEVNULL)
        rt_time += time.perf_counter() - start
        rt_images.append(read_exr(bpy, out))

        out = os.path.join(folder, f"cycles-{k}.exr")
        scene.cycles.samples = per_batch
        scene.cycles.seed = k
        scene.render.filepath = os.path.abspath(out)
        start = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        cy_time += time.perf_counter() - start
        cy_images.append(read_exr(bpy, out))
        if mi_scene is not None:
            start = time.perf_counter()
            mi_images.append(np.array(mi.render(mi_scene, spp=per_batch, seed=k), dtype=np.float64)[:, :, :3])
            mi_time += time.perf_counter() - start
        print(f"batch {k + 1}/{args.batches}: rt-view {rt_time:.1f} s, Cycles {cy_time:.1f} s so far", flush=True)

    rt_blocks = np.stack([block_means(im, args.block) for im in rt_images])
    cy_blocks = np.stack([block_means(im, args.block) for im in cy_images])
    n = args.batches
    rt_mean, cy_mean = rt_blocks.mean(0), cy_blocks.mean(0)
    rt_se = rt_blocks.std(0, ddof=1) / math.sqrt(n)
    cy_se = cy_blocks.std(0, ddof=1) / math.sqrt(n)
    bound = args.z * np.sqrt(rt_se**2 + cy_se**2) + args.rel * np.maximum(np.abs(rt_mean), np.abs(cy_mean))
    agree = (np.abs(rt_mean - cy_mean) <= bound).all(axis=2)
    fraction = agree.mean()

    rt_image = np.mean(rt_images, axis=0)
    cy_image = np.mean(cy_images, axis=0)
    rt_total, cy_total = rt_image.mean(axis=(0, 1)), cy_image.mean(axis=(0, 1))
    ratio = rt_total / np.maximum(cy_total, 1e-30)
    rt_total_se = np.array([im.mean(axis=(0, 1)) for im in rt_images]).std(0, ddof=1) / math.sqrt(n)
    cy_total_se = np.array([im.mean(axis=(0, 1)) for im in cy_images]).std(0, ddof=1) / math.sqrt(n)
    total_z = (rt_total - cy_total) / np.maximum(np.sqrt(rt_total_se**2 + cy_total_se**2), 1e-30)
    z_scores, z_line = block_z(rt_mean, rt_se, cy_mean, cy_se)

    distribution = "multiple-scattering GGX" if args.multiscatter else "single-scattering GGX"
    lines = [
        f"# {name}: rt-view against Blender {bpy.app.version_string} Cycles ({distribution})",
        "",
        f"- {width}×{height}, {per_batch * n} samples per pixel each, in {n} independent batches;"
        f" {args.threads} threads",
        f"- blocks of {args.block}×{args.block}: {agree.sum()} of {agree.size} agree"
        f" ({100 * fraction:.1f} %) within {args.z} standard errors + {100 * args.rel:g} %",
        f"- {z_line}",
        f"- whole-image mean, rt-view / Cycles: R {ratio[0]:.4f}, G {ratio[1]:.4f}, B {ratio[2]:.4f}"
        f" (rt-view {rt_total.round(5).tolist()}, Cycles {cy_total.round(5).tolist()};"
        f" z {total_z.round(1).tolist()})",
        f"- render time: rt-view {rt_time:.2f} s, Cycles {cy_time:.2f} s (Cycles' includes its scene sync)",
    ]
    worst = np.argsort(-np.abs(z_scores).max(axis=2), axis=None)[:5]
    for index in worst:
        by, bx = np.unravel_index(index, agree.shape)
        lines.append(
            f"  - block ({bx}, {by}): rt-view {rt_mean[by, bx].round(4).tolist()} ± {rt_se[by, bx].round(4).tolist()},"
            f" Cycles {cy_mean[by, bx].round(4).tolist()} ± {cy_se[by, bx].round(4).tolist()}"
        )
    if mi_images:
        for label, a, b in (("Mitsuba / Cycles", mi_images, cy_images), ("rt-view / Mitsuba", rt_images, mi_images)):
            agree_ab, ratio_ab = agreement(a, b, args.block, args.z, args.rel)
            lines.append(
                f"- {label} ({args.variant}, {mi_time:.1f} s): {agree_ab.sum()} of {agree_ab.size} blocks agree"
                f" ({100 * agree_ab.mean():.1f} %); image means R {ratio_ab[0]:.4f}, G {ratio_ab[1]:.4f}, B {ratio_ab[2]:.4f}"
            )
    discs = [d for d in object_discs(bpy, scene, width, height) if disc_mean(rt_images[0], *d[1:]) is not None]
    if discs:
        head = "| object | rt-view / Cycles (luminance) ± 2 se | rt-view (RGB) | Cycles (RGB) |"
        head += " Mitsuba / Cycles | rt-view / Mitsuba |" if mi_images else ""
        lines += ["", head, "|---" * head.count(" | ") + "|---|"]
        for obj, cx, cy, r in discs:
            q, se2 = disc_ratio(rt_images, cy_images, cx, cy, r)
            row = f"| {obj} | {q:.3f} ± {se2:.3f} | {np.mean([disc_mean(im, cx, cy, r) for im in rt_images], axis=0).round(4).tolist()} |"
            row += f" {np.mean([disc_mean(im, cx, cy, r) for im in cy_images], axis=0).round(4).tolist()} |"
            if mi_images:
                row += " {:.3f} ± {:.3f} |".format(*disc_ratio(mi_images, cy_images, cx, cy, r))
                row += " {:.3f} ± {:.3f} |".format(*disc_ratio(rt_images, mi_images, cx, cy, r))
            lines.append(row)
    report = "\n".join(lines) + "\n"
    print(report)
    with open(os.path.join(folder, "report.md"), "w") as f:
        f.write(report)

    # Pictures: rt-view | Cycles | blocks that disagree (red) | signed z.
    marks = srgb(cy_image).copy()
    for by, bx in zip(*np.nonzero(~agree)):
        y0, x0 = by * args.block, bx * args.block
        part = marks[y0 : y0 + args.block, x0 : x0 + args.block]
        marks[y0 : y0 + args.block, x0 : x0 + args.block] = part // 2 + np.array([127, 0, 0], dtype=np.uint8)
    # The signed z-score of each block's luminance: red where rt-view is
    # brighter, blue where Cycles is, full colour at 5 standard errors.
    zl = z_scores.mean(axis=2)
    heat = np.zeros(zl.shape + (3,), dtype=np.uint8)
    heat[..., 0] = np.clip(zl / 5, 0, 1) * 255
    heat[..., 2] = np.clip(-zl / 5, 0, 1) * 255
    heat = np.kron(heat, np.ones((args.block, args.block, 1), dtype=np.uint8))
    full = np.zeros_like(marks)
    full[: heat.shape[0], : heat.shape[1]] = heat
    picture = np.concatenate([srgb(rt_image), srgb(cy_image), marks, full], axis=1)
    write_png(bpy, os.path.join(folder, "compare.png"), picture)
    np.save(os.path.join(folder, "rt-view.npy"), rt_image.astype(np.float32))
    np.save(os.path.join(folder, "cycles.npy"), cy_image.astype(np.float32))
    if mi_images:
        np.save(os.path.join(folder, "mitsuba.npy"), np.mean(mi_images, axis=0).astype(np.float32))
    passed = fraction >= 0.99 and np.all(np.abs(ratio - 1) <= 0.01)
    sys.exit(0 if passed else 1)


if __name__ == "__main__":
    main()
