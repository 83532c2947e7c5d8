#!/usr/bin/env python3
"""rt-view beside Blender Cycles (and Mitsuba 3) under the same HDR
environment map, with or without a thin lens; and the skies of the three.

    python3.11 -m venv venv-bpy && venv-bpy/bin/pip install bpy==5.0.1 numpy mitsuba
    cargo build --release -p rt-view
    B=venv-bpy/bin/python
    $B bench/cycles_env_compare.py convention               # where a marked texel lands in each
    $B bench/cycles_env_compare.py compare bench/scenes/envmap_spheres.ron --mitsuba
    $B bench/cycles_env_compare.py compare scenes/depth_of_field.ron --mitsuba
    $B bench/cycles_env_compare.py compare bench/scenes/envmap_floor.ron --mitsuba
    $B bench/cycles_env_compare.py rows                     # where Mitsuba's envmap puts a texel
    $B bench/cycles_env_compare.py sky                      # Preetham / Hosek–Wilkie numbers

`compare` exports the scene with `rt-view export` and builds it in Blender
directly (no file format between them), through bench/common/cycles.py
(which also converts mirrors, glass, emitters and media; the scenes here
use the following):

- rt-view's world is left-handed with +y up, Blender's right-handed with +z
  up: a point (x, y, z) is Blender's (−x, −z, y) (the x mirror of
  bench/mitsuba_compare.py, then y-up to z-up), triangles are rewound.
  Spheres are UV spheres of 256 × 128 segments, smooth shaded.
- the map: rt-view's u = ½ looks along +z, which is Blender's −Y; Cycles'
  Environment Texture puts u = ½ on +X and turns the other way round the
  same axis, so its lookup vector is the view direction turned about +Z by
  90° + ρ (a Mapping node), ρ being rt-view's `rotation`. `convention`
  checks it: a map with one bright marked texel, looked at by both with and
  without a rotation, the spot found in each.
  The map is handed to every renderer as the same float32 OpenEXR (decoded
  from the scene's .hdr once, by Mitsuba's reader, m·2^(e−136) as the
  `image` crate's), so the comparison does not rest on three RGBE readers
  agreeing (on scenes/studio.hdr Blender's and Mitsuba's do, to 4·10⁻⁵ in
  the mean).
- a material `(1 − ks)·diffuse + ks·GGX` (rt-view's legacy material, no
  mirror, glass or emission) is a Mix Shader of a Diffuse BSDF (colour
  kd·colour) and a Glossy BSDF (`GGX`, single scattering, roughness √α
  with α the export's `roughness`, colour the specular colour: a
  Fresnel-free conductor as rt-view's glossy lobe).
- the camera: the same eye, centre of interest and up, vertical field of
  view; a thin lens of radius A focused at f becomes Cycles' depth of field
  with `focus_distance` f and `aperture_fstop = focal length / 2A` (Cycles'
  lens radius is focal length / (2·f-number), the focal length in metres
  as one scene unit), a round aperture (`aperture_blades` 0).
- Cycles as bench/cycles_compare.py sets it up: box pixel filter of 1 pixel,
  no denoising, adaptive sampling, clamping, glossy filter or path guiding;
  bounces max_bounces − 1.

Statistics as bench/cycles_compare.py: `--batches` independent images a
renderer, block means over 16×16 pixels, agreement within Z standard errors
of the difference + `--rel`, whole-image means and their z-score. With
`--mitsuba` Mitsuba 3 renders the same export (bench/mitsuba_compare.py's
conversion, the same EXR) as a third opinion.

`rows` finds where Mitsuba 3's `envmap` puts a texel (row j at
v = j/(H − 1), where rt-view and Cycles use (j + ½)/H) and what that does
to the irradiance of scenes/studio.hdr on an upward surface.

`sky` compares the skies without rendering a scene: rt-view's baked
Preetham map (`rt-view export` of a scene with a `Sky`), Cycles' Sky
Texture (`PREETHAM` and `HOSEK_WILKIE`, still in Blender 5.0 beside the two
Nishita-based models) seen through an equirectangular panoramic camera, and
Mitsuba 3.9's `sunsky` (Hosek–Wilkie) evaluated direction by direction.
"""

import argparse
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
from common.cycles import to_blender  # noqa: E402


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("mode", choices=["convention", "compare", "sky", "rows"])
    p.add_argument("scene", nargs="?", help="rt-view scene (.ron) with an environment Map, for compare")
    p.add_argument("--spp", type=int, default=256, help="samples per pixel in all, each renderer")
    p.add_argument("--batches", type=int, default=8, help="independent images the samples are split into")
    p.add_argument("--rt-view", default="target/release/rt-view", help="the rt-view binary")
    p.add_argument("--out", default="cycles-env-out", help="folder for images and the report")
    p.add_argument("--threads", type=int, default=os.cpu_count(), help="threads for every renderer")
    p.add_argument("--block", type=int, default=16, help="block side in pixels")
    p.add_argument("--z", type=float, default=3.0, help="standard errors a block may differ by")
    p.add_argument("--rel", type=float, default=0.01, help="relative tolerance added to the noise bound")
    p.add_argument("--width", type=int, help="override the image width")
    p.add_argument("--height", type=int, help="override the image height")
    p.add_argument("--mitsuba", action="store_true", help="render a third image with Mitsuba 3")
    p.add_argument("--aperture-scale", type=float, default=1.0,
                   help="multiplies the lens radius Cycles gets: shows that the block test sees a wrong aperture")
    p.add_argument("--exposure", type=float, default=0.0, help="compare: stops applied to the pictures only")
    p.add_argument("--turbidity", type=float, default=3.0, help="sky: turbidity")
    p.add_argument("--elevation", type=float, default=35.0, help="sky: sun elevation in degrees")
    return p.parse_args()


def run(command, threads):
    env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
    subprocess.run(command, check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def write_exr(path, rgb):
    """A float32 linear OpenEXR of rows top to bottom (Mitsuba's writer:
    Blender's `Image.save` writes display-encoded values into an EXR)."""
    import mitsuba as mi

    from mitsuba_compare import bitmap_io

    if not mi.variant():
        mi.set_variant("scalar_rgb")
    with bitmap_io():
        mi.Bitmap(np.ascontiguousarray(rgb, dtype=np.float32)).write(path)


def read_hdr_plain(path):
    """A Radiance .hdr decoded as the `image` crate and Mitsuba do,
    m·2^(e−136) (Mitsuba 3's reader)."""
    import mitsuba as mi

    from mitsuba_compare import bitmap_io

    if not mi.variant():
        mi.set_variant("scalar_rgb")
    with bitmap_io():
        return np.array(mi.Bitmap(path), dtype=np.float32)[:, :, :3]


def environment_world(bpy, exr, strength, rotation_degrees):
    """A world of the map `exr` in rt-view's convention (module comment)."""
    world = bpy.data.worlds.new("environment")
    world.use_nodes = True
    nodes, links = world.node_tree.nodes, world.node_tree.links
    coords = nodes.new("ShaderNodeTexCoord")
    mapping = nodes.new("ShaderNodeMapping")
    mapping.vector_type = "POINT"
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(90.0 + rotation_degrees))
    tex = nodes.new("ShaderNodeTexEnvironment")
    tex.image = bpy.data.images.load(os.path.abspath(exr), check_existing=True)
    tex.image.colorspace_settings.name = "Linear Rec.709"
    tex.interpolation = "Linear"
    tex.projection = "EQUIRECTANGULAR"
    links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    links.new(mapping.outputs["Vector"], tex.inputs["Vector"])
    links.new(tex.outputs["Color"], nodes["Background"].inputs["Color"])
    nodes["Background"].inputs["Strength"].default_value = strength
    return world


def blender_scene(bpy, desc, folder, exr, width, height, threads, aperture_scale=1.0):
    """Blender's scene of an rt-view export under its map (module comment)."""
    env = desc["environment"]
    if env.get("sun"):
        sys.exit("the environment has a sun disc: not converted")
    world = lambda: environment_world(bpy, exr, env["strength"], env["rotation_degrees"])  # noqa: E731
    return cycles.scene_from_export(bpy, desc, folder, width, height, threads, world, aperture_scale)


def scene_with_map(scene_path, exr, folder):
    """A copy of the .ron whose Map reads `exr` (an absolute path)."""
    with open(scene_path) as f:
        text = f.read()
    text, n = re.subn(r'(Map\(\s*file:\s*)"[^"]*"', lambda m: f'{m.group(1)}"{os.path.abspath(exr)}"', text)
    if n != 1:
        sys.exit(f"{scene_path}: needs exactly one `environment: Map(file: …)`")
    # Relative paths of meshes stay relative to the original scene's folder.
    base = os.path.dirname(os.path.abspath(scene_path))
    text = re.sub(
        r'(file:\s*)"([^"/][^"]*\.(?:obj|glb|gltf))"', lambda m: f'{m.group(1)}"{os.path.join(base, m.group(2))}"', text
    )
    out = os.path.join(folder, "scene.ron")
    with open(out, "w") as f:
        f.write(text)
    return out


def render_cycles(bpy, scene, out, spp, seed):
    scene.cycles.samples = spp
    scene.cycles.seed = seed
    scene.render.filepath = os.path.abspath(out)
    bpy.ops.render.render(write_still=True)


def compare(args):
    import bpy
    import json

    from common.cycles import read_exr, write_png
    from common.images import agreement, block_means, srgb

    name = os.path.splitext(os.path.basename(args.scene))[0]
    folder = os.path.abspath(os.path.join(args.out, name))
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    with open(args.scene) as f:
        m = re.search(r'Map\(\s*file:\s*"([^"]+)"', f.read())
    if not m:
        sys.exit(f"{args.scene}: has no environment Map")
    source = os.path.join(os.path.dirname(args.scene), m.group(1))
    exr = os.path.join(folder, "map.exr")
    texels = read_hdr_plain(source) if source.endswith(".hdr") else None
    if texels is None:
        shutil.copy(source, exr)
    else:
        write_exr(exr, texels)
    ron = scene_with_map(args.scene, exr, folder)
    subprocess.run([args.rt_view, "export", ron, "-o", os.path.join(folder, "scene.json")], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(os.path.join(folder, "scene.json")) as f:
        desc = json.load(f)
    width = args.width or desc["width"]
    height = args.height or desc["height"]
    per_batch = max(1, args.spp // args.batches)
    scene = blender_scene(bpy, desc, folder, exr, width, height, args.threads, args.aperture_scale)

    mi_scene = None
    if args.mitsuba:
        import drjit as dr
        import mitsuba as mi

        from mitsuba_compare import mitsuba_scene

        dr.set_thread_count(args.threads)
        mdesc = json.loads(json.dumps(desc))
        mdesc["environment"]["file"] = exr  # an absolute path: os.path.join keeps it
        mi_scene = mi.load_dict(mitsuba_scene(mi, mdesc, folder, width, height, 400.0))

    images = {"rt-view": [], "Cycles": [], "Mitsuba": []}
    times = dict.fromkeys(images, 0.0)
    for k in range(args.batches):
        out = os.path.join(folder, f"rt-{k}.exr")
        start = time.perf_counter()
        run([args.rt_view, "render", ron, "-o", out, "--spp", str(per_batch), "--seed", str(k),
             "--width", str(width), "--height", str(height)], args.threads)
        times["rt-view"] += time.perf_counter() - start
        images["rt-view"].append(read_exr(bpy, out))
        out = os.path.join(folder, f"cycles-{k}.exr")
        start = time.perf_counter()
        render_cycles(bpy, scene, out, per_batch, k)
        times["Cycles"] += time.perf_counter() - start
        images["Cycles"].append(read_exr(bpy, out))
        if mi_scene is not None:
            start = time.perf_counter()
            images["Mitsuba"].append(np.array(mi.render(mi_scene, spp=per_batch, seed=k), dtype=np.float64)[:, :, :3])
            times["Mitsuba"] += time.perf_counter() - start
        print(f"batch {k + 1}/{args.batches}: " + ", ".join(f"{n} {t:.1f} s" for n, t in times.items() if t), flush=True)

    n = args.batches
    lines = [
        f"# {name}: rt-view, Blender {bpy.app.version_string} Cycles"
        + (" and Mitsuba 3" if mi_scene is not None else ""),
        "",
        f"- {width}×{height}, {per_batch * n} samples per pixel each, in {n} independent batches; {args.threads} threads;"
        f" blocks of {args.block}×{args.block} agree within {args.z} standard errors + {100 * args.rel:g} %",
        "- render time: " + ", ".join(f"{k} {t:.1f} s" for k, t in times.items() if t),
        "",
        "| pair | blocks that agree | median / max block \\|z\\| | image mean ratio R, G, B | z of the image means |",
        "|---|---:|---:|---:|---:|",
    ]
    pairs = [("rt-view", "Cycles")]
    if mi_scene is not None:
        pairs += [("rt-view", "Mitsuba"), ("Mitsuba", "Cycles")]
    cy_agree = None
    for a, b in pairs:
        agree, ratio = agreement(images[a], images[b], args.block, args.z, args.rel)
        ba = np.stack([block_means(im, args.block) for im in images[a]])
        bb = np.stack([block_means(im, args.block) for im in images[b]])
        z = (ba.mean(0) - bb.mean(0)) / np.maximum(
            np.sqrt(ba.var(0, ddof=1) / n + bb.var(0, ddof=1) / n), 1e-30
        )
        ta = np.array([im.mean(axis=(0, 1)) for im in images[a]])
        tb = np.array([im.mean(axis=(0, 1)) for im in images[b]])
        tz = (ta.mean(0) - tb.mean(0)) / np.sqrt(ta.var(0, ddof=1) / n + tb.var(0, ddof=1) / n)
        lines.append(
            f"| {a} / {b} | {agree.sum()} of {agree.size} ({100 * agree.mean():.1f} %) |"
            f" {np.median(np.abs(z)):.2f} / {np.abs(z).max():.1f} |"
            f" {ratio[0]:.4f}, {ratio[1]:.4f}, {ratio[2]:.4f} | {tz[0]:.1f}, {tz[1]:.1f}, {tz[2]:.1f} |"
        )
        if cy_agree is None:
            cy_agree, cy_z = agree, z
    report = "\n".join(lines) + "\n"
    print(report)
    with open(os.path.join(folder, "report.md"), "w") as f:
        f.write(report)
    rt_image = np.mean(images["rt-view"], axis=0)
    cy_image = np.mean(images["Cycles"], axis=0)
    gain = 2.0**args.exposure
    marks = srgb(gain * cy_image).copy()
    for by, bx in zip(*np.nonzero(~cy_agree)):
        y0, x0 = by * args.block, bx * args.block
        part = marks[y0 : y0 + args.block, x0 : x0 + args.block]
        marks[y0 : y0 + args.block, x0 : x0 + args.block] = part // 2 + np.array([127, 0, 0], dtype=np.uint8)
    zl = cy_z.mean(axis=2)
    heat = np.zeros(zl.shape + (3,), dtype=np.uint8)
    heat[..., 0] = np.clip(zl / 5, 0, 1) * 255
    heat[..., 2] = np.clip(-zl / 5, 0, 1) * 255
    heat = np.kron(heat, np.ones((args.block, args.block, 1), dtype=np.uint8))
    full = np.zeros_like(marks)
    full[: heat.shape[0], : heat.shape[1]] = heat
    write_png(bpy, os.path.join(folder, "compare.png"), np.concatenate([srgb(gain * rt_image), srgb(gain * cy_image), marks, full], axis=1))
    for k, ims in images.items():
        if ims:
            np.save(os.path.join(folder, f"{k}.npy"), np.mean(ims, axis=0).astype(np.float32))


def convention(args):
    """A map with one bright texel seen by both renderers, for rotations 0
    and 30°: where does the spot land in each image?"""
    import bpy
    import json

    from common.cycles import read_exr

    folder = os.path.abspath(os.path.join(args.out, "convention"))
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    w, h = 64, 32
    texels = np.full((h, w, 3), 0.05, dtype=np.float32)
    i, j = 26, 11  # u = 26.5/64 ≈ 0.414 (31° left of ahead), v = 11.5/32 ≈ 0.359 (25° up)
    texels[j, i] = (1000.0, 0.0, 0.0)
    texels[j + 1, i] = (0.0, 0.0, 300.0)  # a blue texel below it: up and down cannot be swapped unseen
    exr = os.path.join(folder, "marked.exr")
    write_exr(exr, texels)
    lines = ["# Where the marked texel lands (pixel column, row of the red spot's brightest pixel)", ""]
    for rotation in (0.0, 30.0):
        ron = os.path.join(folder, f"marked-{rotation:g}.ron")
        with open(ron, "w") as f:
            f.write(
                "Scene(\n"
                "    camera: (position: (0, 0, 0), center_of_interest: (0, 0, 1), up: (0, 1, 0), fov_y: 90, near: 1),\n"
                "    image: (width: 160, height: 120),\n"
                f'    environment: Map(file: "{exr}", strength: 1, rotation: {rotation}),\n'
                '    materials: { "grey": (color: (0.5, 0.5, 0.5)) },\n'
                "    objects: [ Sphere(center: (0, -1000, 0), radius: 1, material: \"grey\") ],\n"
                "    effects: (global_illumination: (max_bounces: 1)),\n"
                ")\n"
            )
        subprocess.run([args.rt_view, "export", ron, "-o", os.path.join(folder, "scene.json")], check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        with open(os.path.join(folder, "scene.json")) as f:
            desc = json.load(f)
        scene = blender_scene(bpy, desc, folder, exr, 160, 120, args.threads)
        rt = os.path.join(folder, f"rt-{rotation:g}.exr")
        run([args.rt_view, "render", ron, "-o", rt, "--spp", "16"], args.threads)
        cy = os.path.join(folder, f"cycles-{rotation:g}.exr")
        render_cycles(bpy, scene, cy, 16, 0)
        # Where rt-view's documented convention puts the texel centre.
        u, v = (i + 0.5) / w, (j + 0.5) / h
        theta, phi = math.pi * v, 2 * math.pi * u
        m = np.array([-math.sin(theta) * math.sin(phi), math.cos(theta), -math.sin(theta) * math.cos(phi)])
        rho = math.radians(rotation)
        d = np.array([m[0] * math.cos(rho) + m[2] * math.sin(rho), m[1], -m[0] * math.sin(rho) + m[2] * math.cos(rho)])
        # rt-view's pinhole looking along +z, +x to the right (left-handed), fov 90°.
        px = (1 + d[0] / d[2] / (160 / 120)) / 2 * 160 if d[2] > 0 else float("nan")
        py = (1 - d[1] / d[2]) / 2 * 120 if d[2] > 0 else float("nan")
        spots = []
        for path in (rt, cy):
            image = read_exr(bpy, path)
            red = image[..., 0] - image[..., 2]
            blue = image[..., 2] - image[..., 0]
            ry, rx = np.unravel_index(np.argmax(red), red.shape)
            by, bx = np.unravel_index(np.argmax(blue), blue.shape)
            spots.append(((int(rx), int(ry)), (int(bx), int(by))))
        lines.append(
            f"- rotation {rotation:g}°: documented convention ({px:.1f}, {py:.1f});"
            f" rt-view red {spots[0][0]} blue {spots[0][1]}; Cycles red {spots[1][0]} blue {spots[1][1]}"
        )
    report = "\n".join(lines) + "\n"
    print(report)
    with open(os.path.join(folder, "report.md"), "w") as f:
        f.write(report)


LUMINANCE = np.array([0.2126, 0.7152, 0.0722])  # Rec.709 / sRGB Y


def rt_direction(u, v):
    """rt-view's direction of map coordinates (u, v) (rotation 0), as an
    array of shape (..., 3), docs/environment-and-lens.md."""
    theta, phi = np.pi * v, 2 * np.pi * u
    return np.stack([-np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)], axis=-1)


def cell_means(image, factor):
    h, w, _ = image.shape
    return image.reshape(h // factor, factor, w // factor, factor, 3).mean(axis=(1, 3))


def cycles_sky(bpy, kind, sun_blender, turbidity, albedo, width, height, out, threads):
    """Cycles' Sky Texture of `kind` through an equirectangular camera,
    turned so that the image is in rt-view's map layout: the camera looks
    along Blender's −Y (rt-view's +z), +Z up."""
    from common.cycles import read_exr

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    world = bpy.data.worlds.new("sky")
    world.use_nodes = True
    node = world.node_tree.nodes.new("ShaderNodeTexSky")
    node.sky_type = kind
    node.sun_direction = sun_blender
    node.turbidity = turbidity
    node.ground_albedo = albedo
    world.node_tree.links.new(node.outputs["Color"], world.node_tree.nodes["Background"].inputs["Color"])
    scene.world = world
    data = bpy.data.cameras.new("pano")
    data.type = "PANO"
    data.panorama_type = "EQUIRECTANGULAR"
    obj = bpy.data.objects.new("pano", data)
    scene.collection.objects.link(obj)
    obj.rotation_euler = (math.pi / 2, 0.0, math.pi)  # −Z → +Y, then turned to −Y
    scene.camera = obj
    cycles.settings(scene, width, height, threads, 0)
    render_cycles(bpy, scene, out, 4, 0)
    return read_exr(bpy, out)


def mitsuba_sky(sun_blender, turbidity, albedo, width, height):
    """Mitsuba 3's `sunsky` (Hosek–Wilkie; its frame is right-handed with +z
    up, as Blender's) at the centres of a width × height grid in rt-view's
    map layout, sky only; and the sun's irradiance on a surface facing it
    (sun only, integrated over a cap of 0.4° around its centre)."""
    import drjit as dr
    import mitsuba as mi

    if not mi.variant():
        mi.set_variant("scalar_rgb")

    def emitter(sun_scale, sky_scale):
        return mi.load_dict({"type": "sunsky", "sun_direction": list(sun_blender), "turbidity": turbidity,
                             "albedo": albedo, "sun_scale": sun_scale, "sky_scale": sky_scale})

    def radiance(e, d):
        si = dr.zeros(mi.SurfaceInteraction3f)
        si.wi = -mi.Vector3f(*[float(x) for x in d])
        return np.array(e.eval(si), dtype=np.float64)

    sky_only = emitter(0.0, 1.0)
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height // 2) + 0.5) / height  # the upper hemisphere
    image = np.zeros((height, width, 3))
    for j, vj in enumerate(v):
        for i, ui in enumerate(u):
            d = rt_direction(ui, vj)
            image[j, i] = radiance(sky_only, to_blender(d))
    sun_only = emitter(1.0, 0.0)
    axis = np.array(sun_blender) / np.linalg.norm(sun_blender)
    a = np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else [1.0, 0.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(axis, a)
    cap, n_t, n_p = math.radians(0.4), 80, 48
    e_sun = np.zeros(3)
    for k in range(n_t):
        t = (k + 0.5) / n_t * cap
        for m in range(n_p):
            p = (m + 0.5) / n_p * 2 * math.pi
            d = math.cos(t) * axis + math.sin(t) * (math.cos(p) * a + math.sin(p) * b)
            e_sun += radiance(sun_only, d) * math.cos(t) * math.sin(t) * (cap / n_t) * (2 * math.pi / n_p)
    return image, e_sun


def hemisphere_facts(image):
    """(zenith RGB, horizontal irradiance RGB) of an upper-hemisphere map in
    rt-view's layout: the zenith the mean of the top row, the irradiance
    Σ L cos θ dω over the rows above the horizon."""
    h, w, _ = image.shape
    v = (np.arange(h) + 0.5) / h
    theta = np.pi * v
    up = theta < np.pi / 2
    d_omega = (np.pi / h) * (2 * np.pi / w) * np.sin(theta)
    e = (image[up] * (np.cos(theta[up]) * d_omega[up])[:, None, None]).sum(axis=(0, 1))
    return image[0].mean(axis=0), e


def sky(args):
    """Preetham (rt-view, Cycles), Hosek–Wilkie (Cycles, Mitsuba): zenith,
    horizon, irradiance, shape. Sizes stated; different models differ."""
    import bpy
    import json

    folder = os.path.abspath(os.path.join(args.out, "sky"))
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    T, elev, albedo = args.turbidity, math.radians(args.elevation), 0.3
    azimuth = math.radians(135.0)  # behind and to the right, as in scenes/outdoor.ron
    d_rt = (math.cos(elev) * math.sin(azimuth), math.sin(elev), math.cos(elev) * math.cos(azimuth))
    d_bl = to_blender(d_rt)
    ron = os.path.join(folder, "sky.ron")
    with open(ron, "w") as f:
        f.write(
            "Scene(\n    camera: (position: (0, 1, 0), center_of_interest: (0, 1, 1), up: (0, 1, 0), fov_y: 60, near: 1),\n"
            "    image: (width: 64, height: 48),\n"
            f"    environment: Sky(sun_direction: ({d_rt[0]!r}, {d_rt[1]!r}, {d_rt[2]!r}), turbidity: {T!r},"
            f" sun_irradiance: (1, 1, 1), ground_albedo: {albedo}),\n"
            '    materials: { "grey": (color: (0.5, 0.5, 0.5)) },\n'
            '    objects: [ Sphere(center: (0, -1000, 0), radius: 1, material: "grey") ],\n)\n'
        )
    subprocess.run([args.rt_view, "export", ron, "-o", os.path.join(folder, "sky.json")], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(os.path.join(folder, "sky.json")) as f:
        desc = json.load(f)
    rt = read_hdr_plain(os.path.join(folder, desc["environment"]["file"])).astype(np.float64)
    h, w, _ = rt.shape
    factor = 4
    grid_w, grid_h = w // factor, h // factor
    maps = {"rt-view Preetham": cell_means(rt, factor)}
    for kind, label in (("PREETHAM", "Cycles Preetham"), ("HOSEK_WILKIE", "Cycles Hosek–Wilkie")):
        image = cycles_sky(bpy, kind, d_bl, T, albedo, w, h, os.path.join(folder, f"{kind.lower()}.exr"), args.threads)
        maps[label] = cell_means(image, factor)
    mi_map, mi_sun = mitsuba_sky(d_bl, T, albedo, grid_w, grid_h)
    maps["Mitsuba Hosek–Wilkie"] = mi_map

    # Preetham's zenith luminance, the paper's formula (kcd/m²).
    theta_s = math.pi / 2 - elev
    chi = (4 / 9 - T / 120) * (math.pi - 2 * theta_s)
    yz = (4.0453 * T - 4.9710) * math.tan(chi) - 0.2155 * T + 2.4192
    lines = [
        f"# Skies at turbidity {T:g}, sun {args.elevation:g}° high, ground albedo {albedo}",
        "",
        f"Preetham's zenith luminance (the paper's formula): {yz:.4f} kcd/m²; rt-view's radiance is Y/10 of it.",
        "",
        "| sky | zenith RGB | zenith Y | Y at 5° elevation: toward the sun / 90° off / away, ÷ zenith"
        " | horizontal sky irradiance E_sky (Y) |",
        "|---|---|---:|---:|---:|",
    ]
    v = (np.arange(grid_h) + 0.5) / grid_h
    u = (np.arange(grid_w) + 0.5) / grid_w
    row5 = int(np.argmin(np.abs((0.5 - v) * 180 - 5)))
    sun_u = (math.atan2(-d_rt[0], -d_rt[2]) / (2 * math.pi)) % 1.0

    def column(offset):
        return int(np.argmin(np.abs(((u - sun_u - offset + 0.5) % 1.0) - 0.5)))

    facts = {}
    for label, image in maps.items():
        zen, e = hemisphere_facts(image)
        lum = image @ LUMINANCE
        zy = zen @ LUMINANCE
        ratios = [lum[row5, column(o)] / zy for o in (0.0, 0.25, 0.5)]
        facts[label] = (zen, zy, e @ LUMINANCE, lum)
        lines.append(
            f"| {label} | {zen.round(4).tolist()} | {zy:.4f} | {ratios[0]:.2f} / {ratios[1]:.2f} / {ratios[2]:.2f}"
            f" | {e @ LUMINANCE:.4f} |"
        )
    up = v < 0.5
    shape = []
    for a, b in (("rt-view Preetham", "Cycles Preetham"), ("Cycles Hosek–Wilkie", "Mitsuba Hosek–Wilkie"),
                 ("rt-view Preetham", "Mitsuba Hosek–Wilkie")):
        la, lb = facts[a][3][up], facts[b][3][up]
        q = la / np.maximum(lb, 1e-12)
        scale = facts[a][1] / facts[b][1]
        rel = q / scale - 1
        shape.append(
            f"- {a} / {b}: zenith {scale:.4f}; over the sky above the horizon, after dividing by the zenith ratio,"
            f" median |difference| {100 * np.median(np.abs(rel)):.1f} %, 95th percentile"
            f" {100 * np.percentile(np.abs(rel), 95):.1f} %, range {100 * rel.min():+.1f} … {100 * rel.max():+.1f} %"
        )
    mi_e = facts["Mitsuba Hosek–Wilkie"][2]
    lines += [
        "",
        *shape,
        "",
        f"- Mitsuba's sun: irradiance on a surface facing it {mi_sun.round(4).tolist()} (Y {mi_sun @ LUMINANCE:.4f});"
        f" on a horizontal surface {mi_sun @ LUMINANCE * math.sin(elev):.4f}, {mi_sun @ LUMINANCE * math.sin(elev) / mi_e:.2f}"
        " times the sky's",
        f"- rt-view's sun is given by its irradiance (here 1, 1, 1); with rt-view's sky the horizontal ratio sun : sky"
        f" for an irradiance E is {math.sin(elev):.3f}·E : {facts['rt-view Preetham'][2]:.4f}",
    ]
    report = "\n".join(lines) + "\n"
    print(report)
    with open(os.path.join(folder, "report.md"), "w") as f:
        f.write(report)
    np.savez(os.path.join(folder, "skies.npz"), **{k.replace(" ", "_"): m for k, m in maps.items()})
    # Picture: the skies above the horizon, one under another in the order
    # of the table, each divided by its own zenith luminance (shape and
    # colour, not scale), ×0.25, sRGB, each texel 2 × 2 pixels.
    from common.cycles import write_png
    from common.images import srgb

    rows = [srgb(0.25 * m[: grid_h // 2] / facts[k][1]) for k, m in maps.items()]
    picture = np.concatenate(rows, axis=0)
    picture = np.kron(picture, np.ones((2, 2, 1), dtype=np.uint8))
    write_png(bpy, os.path.join(folder, "skies.png"), picture)


def rows(args):
    """Where Mitsuba 3's `envmap` puts a map's texels, against the texel
    centres ((i + ½)/W, (j + ½)/H) of rt-view and Cycles: the peak of one
    marked texel's lookup, and the irradiance of scenes/studio.hdr on an
    upward surface by quadrature of each lookup (what
    bench/scenes/envmap_floor.ron renders, times 0.5/π)."""
    import drjit as dr
    import mitsuba as mi

    if not mi.variant():
        mi.set_variant("scalar_rgb")
    folder = os.path.abspath(os.path.join(args.out, "rows"))
    os.makedirs(folder, exist_ok=True)

    def mitsuba_lookup(path):
        em = mi.load_dict({"type": "envmap", "filename": path})

        def at(u, v):
            d = rt_direction(u, v)
            si = dr.zeros(mi.SurfaceInteraction3f)
            si.wi = -mi.Vector3f(-float(d[0]), float(d[1]), float(d[2]))  # Mitsuba's frame: x mirrored
            return np.array(em.eval(si), dtype=np.float64)

        return at

    W, H, i, j = 64, 32, 26, 11
    marked = np.zeros((H, W, 3), dtype=np.float32)
    marked[j, i] = 1.0
    path = os.path.join(folder, "one-texel.exr")
    write_exr(path, marked)
    at = mitsuba_lookup(path)
    us = np.linspace((i - 1.5) / W, (i + 2.5) / W, 801)
    vs = np.linspace((j - 1.5) / H, (j + 2.5) / H, 801)
    pu = np.array([at(u, (j + 0.5) / H)[0] for u in us])
    pv = np.array([at((i + 0.5) / W, v)[0] for v in vs])
    lines = [
        f"# Texel ({i}, {j}) of a {W} × {H} map",
        "",
        f"- Mitsuba's lookup peaks at column {us[pu.argmax()] * W:.3f} (texel centre {i + 0.5}),"
        f" row {vs[pv.argmax()] * H:.3f} (texel centre {j + 0.5}; j·H/(H − 1) = {j * H / (H - 1):.3f})",
    ]

    t = read_hdr_plain(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes", "studio.hdr"))
    t = t.astype(np.float64)
    h, w, _ = t.shape
    n_u, n_v = 4096, 2048
    u = (np.arange(n_u) + 0.5) / n_u
    v = (np.arange(n_v) + 0.5) / n_v * 0.5

    def bilinear(x, y):
        i0, j0 = np.floor(x).astype(int), np.floor(y).astype(int)
        fx, fy = x - i0, y - j0
        rows0, rows1 = t[np.clip(j0, 0, h - 1)], t[np.clip(j0 + 1, 0, h - 1)]
        a = rows0[:, i0 % w] * (1 - fx)[None, :, None] + rows0[:, (i0 + 1) % w] * fx[None, :, None]
        b = rows1[:, i0 % w] * (1 - fx)[None, :, None] + rows1[:, (i0 + 1) % w] * fx[None, :, None]
        return a * (1 - fy)[:, None, None] + b * fy[:, None, None]

    theta = np.pi * v
    weight = np.sin(theta) * np.cos(theta) * (np.pi * 0.5 / n_v) * (2 * np.pi / n_u)
    centres = (bilinear(u * w - 0.5, v * h - 0.5) * weight[:, None, None]).sum(axis=(0, 1))
    vertices = (bilinear(u * w - 0.5, v * (h - 1)) * weight[:, None, None]).sum(axis=(0, 1))
    lines += [
        "",
        "scenes/studio.hdr, irradiance on an upward surface (RGB), 4096 × 1024 quadrature:",
        f"- texel centres ((i + ½)/W, (j + ½)/H), rt-view and Cycles: {centres.round(4).tolist()};"
        f" a floor of albedo 0.5 shows {(0.5 / np.pi * centres).round(4).tolist()}",
        f"- rows at j/(H − 1), Mitsuba: {vertices.round(4).tolist()} ({100 * (vertices / centres - 1).mean():+.2f} %);"
        f" the floor {(0.5 / np.pi * vertices).round(4).tolist()}",
    ]
    report = "\n".join(lines) + "\n"
    print(report)
    with open(os.path.join(folder, "report.md"), "w") as f:
        f.write(report)


if __name__ == "__main__":
    a = parse_args()
    if a.mode == "compare":
        if not a.scene:
            sys.exit("compare needs a scene")
        compare(a)
    elif a.mode == "convention":
        convention(a)
    elif a.mode == "rows":
        rows(a)
    else:
        sky(a)
