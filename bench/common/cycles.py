"""Blender Cycles set up to render what rt-view renders: the settings every
bench script uses, and a scene built from `rt-view export` JSON.

Settings (`settings`): CPU, a fixed thread count, a box pixel filter of 1
pixel (rt-view spreads its samples uniformly over each pixel), no
denoising, no adaptive sampling, no clamping, no glossy filter, reflective
and refractive caustics on, no light-sampling threshold, no path guiding;
bounces max_bounces − 1 for every kind (rt-view's 1 is direct lighting,
Cycles' 0); linear OpenEXR output. The sampling pattern is left at Cycles'
default (its scrambled Sobol / blue-noise sequences). Callers turn
adaptive sampling and OIDN on where they measure them.

Scene from an export (`scene_from_export`):

- rt-view's world is left-handed with +y up, Blender's right-handed with +z
  up: a point (x, y, z) is Blender's (−x, −z, y) (the x mirror of
  bench/mitsuba_compare.py, then y-up to z-up); triangles are rewound so
  every face keeps the side its normal points to. Spheres are UV spheres
  of 256 × 128 segments, smooth shaded; an infinite plane is a square
  `plane_size` wide centred below the centre of interest.
- the camera: the same eye, centre of interest and up, vertical field of
  view; a thin lens of radius A focused at f becomes Cycles' depth of field
  with `focus_distance` f and `aperture_fstop = focal length / 2A`.
- a legacy material `(1 − kr − kt)·[(1 − ks)·diffuse + ks·GGX] + kr·mirror
  + kt·glass` (docs/effects.md) is a tree of Mix Shaders: Diffuse BSDF
  (kd·colour), Glossy BSDF (`GGX`, roughness √α, the specular colour: a
  Fresnel-free conductor as rt-view's glossy lobe), a sharp Glossy BSDF of
  the specular colour for the mirror, a sharp Glass BSDF of the colour and
  IOR for the glass (Cycles' Glass tints its reflection too, rt-view's
  only the transmission: the same for white glass).
- emission is an Emission shader of the material's radiance added to the
  surface, zero on back faces (rt-view's emitters are one-sided), with the
  material's emission sampling set to front faces.
- a material with `subsurface` (rt-view's random walk in a homogeneous
  medium behind a smooth dielectric boundary, docs/subsurface) is the same
  thing in Cycles: a sharp Glass BSDF of its IOR (Transparent at IOR 1)
  around a homogeneous volume of Volume Scatter (σs = albedo/mfp, its
  Henyey–Greenstein anisotropy) plus Volume Absorption (σa = (1 −
  albedo)/mfp), not the Principled BSDF's subsurface (a BSSRDF
  parameterised by radius, another model). Volume and total bounces are
  then 1024 (Cycles' most), as Mitsuba's volpath runs without a limit.
- a physical (glTF) material is a Principled BSDF with its base colour,
  metallic, roughness, IOR, transmission and coat (Cycles' Principled v2,
  close to but not glTF's model: docs/models.md).
- point lights are Cycles point lights of radius 0 and power 4π·I (Cycles
  spreads a point light's watts over 4π sr), directional lights suns of
  angle 0 and strength E; the background a uniform world of its colour.
"""

import math
import os
import sys

import numpy as np


def to_blender(p):
    """rt-view's left-handed, y-up point or direction in Blender's frame."""
    return (-p[0], -p[2], p[1])


def settings(scene, width, height, threads, bounces):
    """Cycles set up as the module comment says."""
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = width, height, 100
    r.threads_mode = "FIXED"
    r.threads = threads
    r.film_transparent = False
    r.use_persistent_data = True
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    r.image_settings.exr_codec = "ZIP"
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    c = scene.cycles
    c.device = "CPU"
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    c.caustics_reflective = True
    c.caustics_refractive = True
    c.light_sampling_threshold = 0.0
    c.use_guiding = False
    c.max_bounces = c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = bounces
    c.transparent_max_bounces = bounces
    c.volume_bounces = 0
    c.use_animated_seed = False


def uniform_world(bpy, colour):
    """A world of one colour, strength 1."""
    world = bpy.data.worlds.new("background")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (*colour, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0
    return world


def camera(bpy, cam_desc, scene, aperture_scale=1.0):
    """A camera at rt-view's eye looking at its centre of interest, the same
    vertical field of view, and its thin lens (module comment)."""
    from mathutils import Matrix, Vector

    data = bpy.data.cameras.new("camera")
    obj = bpy.data.objects.new("camera", data)
    scene.collection.objects.link(obj)
    eye = Vector(to_blender(cam_desc["position"]))
    target = Vector(to_blender(cam_desc["center_of_interest"]))
    up = Vector(to_blender(cam_desc["up"]))
    forward = (target - eye).normalized()
    right = forward.cross(up).normalized()
    true_up = right.cross(forward)
    rot = Matrix((right, true_up, -forward)).transposed()
    obj.matrix_world = Matrix.Translation(eye) @ rot.to_4x4()
    data.sensor_fit = "VERTICAL"
    data.angle_y = math.radians(cam_desc["fov_y"])
    data.clip_start = 1e-3
    data.clip_end = 1e5
    aperture = cam_desc.get("aperture", 0.0) * aperture_scale
    if aperture > 0:
        data.dof.use_dof = True
        data.dof.focus_distance = cam_desc["focus_distance"]
        data.dof.aperture_fstop = data.lens * 1e-3 / (2.0 * aperture)
        data.dof.aperture_blades = 0
        data.dof.aperture_ratio = 1.0
    scene.camera = obj
    return obj


def _mix(links, nodes, factor, a, b):
    """(1 − factor)·a + factor·b, skipping a node whose weight is 0."""
    if factor <= 0 or b is None:
        return a
    if factor >= 1 or a is None:
        return b
    mix = nodes.new("ShaderNodeMixShader")
    mix.inputs["Fac"].default_value = factor
    links.new(a, mix.inputs[1])
    links.new(b, mix.inputs[2])
    return mix.outputs["Shader"]


def _glass(nodes, colour, ior):
    glass = nodes.new("ShaderNodeBsdfGlass")
    glass.distribution = "GGX"  # roughness 0: Cycles treats it as a smooth (δ) interface
    glass.inputs["Roughness"].default_value = 0.0
    glass.inputs["Color"].default_value = (*colour, 1.0)
    glass.inputs["IOR"].default_value = ior
    return glass.outputs["BSDF"]


def _legacy_surface(nodes, links, m):
    kr, kt, ks, kd = m["reflectivity"], m["transparency"], m["specular"], m["diffuse"]
    tint = m.get("specular_color", [1.0, 1.0, 1.0])
    rest = None
    if kd > 0 and max(m["color"]) > 0:
        diffuse = nodes.new("ShaderNodeBsdfDiffuse")
        diffuse.inputs["Color"].default_value = (*[kd * c for c in m["color"]], 1.0)
        diffuse.inputs["Roughness"].default_value = 0.0
        rest = diffuse.outputs["BSDF"]
    glossy_out = None
    if ks > 0:
        glossy = nodes.new("ShaderNodeBsdfGlossy")
        glossy.distribution = "GGX"
        glossy.inputs["Color"].default_value = (*tint, 1.0)
        glossy.inputs["Roughness"].default_value = math.sqrt(m["roughness"])
        glossy_out = glossy.outputs["BSDF"]
    if rest is None and glossy_out is not None:
        rest = _mix(links, nodes, 1.0, None, glossy_out)
    else:
        rest = _mix(links, nodes, ks, rest, glossy_out)
    delta = kr + kt
    deltas = None
    if delta > 0:
        mirror = None
        if kr > 0:
            node = nodes.new("ShaderNodeBsdfGlossy")
            node.distribution = "GGX"
            node.inputs["Roughness"].default_value = 0.0
            node.inputs["Color"].default_value = (*tint, 1.0)
            mirror = node.outputs["BSDF"]
        glass = _glass(nodes, m["color"], m["ior"]) if kt > 0 else None
        deltas = _mix(links, nodes, kt / delta, mirror, glass)
    if rest is None and deltas is None:
        black = nodes.new("ShaderNodeBsdfDiffuse")
        black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        return black.outputs["BSDF"]
    if rest is None:
        # Only δ lobes: kr + kt of them, the rest black.
        if delta >= 1:
            return deltas
        black = nodes.new("ShaderNodeBsdfDiffuse")
        black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        rest = black.outputs["BSDF"]
    return _mix(links, nodes, delta, rest, deltas)


def _physical_surface(nodes, m):
    p = m["physical"]
    node = nodes.new("ShaderNodeBsdfPrincipled")
    node.distribution = "GGX"
    node.inputs["Base Color"].default_value = (*m["color"], 1.0)
    node.inputs["Metallic"].default_value = p["metallic"]
    node.inputs["Roughness"].default_value = p["roughness"]
    node.inputs["IOR"].default_value = max(m["ior"], 1.0001)
    node.inputs["Transmission Weight"].default_value = p["transmission"]
    node.inputs["Coat Weight"].default_value = p["clearcoat"]
    node.inputs["Coat Roughness"].default_value = p["clearcoat_roughness"]
    return node.outputs["BSDF"]


def material(bpy, m):
    """The Cycles material of an rt-view material (module comment); returns
    it and whether it holds a medium."""
    if m.get("textured"):
        sys.exit(f"material {m['name']!r}: textures are not exported")
    mat = bpy.data.materials.new(m["name"])
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    for n in list(nodes):
        if n.type != "OUTPUT_MATERIAL":
            nodes.remove(n)
    out = next(n for n in nodes if n.type == "OUTPUT_MATERIAL")
    medium = m.get("subsurface")
    if medium:
        if m["ior"] == 1.0:
            surface = nodes.new("ShaderNodeBsdfTransparent").outputs["BSDF"]
        else:
            surface = _glass(nodes, [1.0, 1.0, 1.0], m["ior"])
        sigma_t = [1.0 / l for l in medium["mean_free_path"]]
        sigma_s = [a * s for a, s in zip(medium["albedo"], sigma_t)]
        sigma_a = [(1.0 - a) * s for a, s in zip(medium["albedo"], sigma_t)]
        scatter = nodes.new("ShaderNodeVolumeScatter")
        scatter.inputs["Density"].default_value = max(sigma_s)
        scatter.inputs["Color"].default_value = (*[s / max(sigma_s) for s in sigma_s], 1.0)
        scatter.inputs["Anisotropy"].default_value = medium["anisotropy"]
        volume = scatter.outputs["Volume"]
        if max(sigma_a) > 0:
            # Cycles' absorption coefficient is density·(1 − colour).
            absorb = nodes.new("ShaderNodeVolumeAbsorption")
            absorb.inputs["Density"].default_value = max(sigma_a)
            absorb.inputs["Color"].default_value = (*[1.0 - s / max(sigma_a) for s in sigma_a], 1.0)
            add = nodes.new("ShaderNodeAddShader")
            links.new(volume, add.inputs[0])
            links.new(absorb.outputs["Volume"], add.inputs[1])
            volume = add.outputs["Shader"]
        links.new(volume, out.inputs["Volume"])
        # Blender 5 has no homogeneous switch: Cycles finds a constant
        # density itself and samples distances analytically.
    elif m.get("physical"):
        surface = _physical_surface(nodes, m)
    else:
        surface = _legacy_surface(nodes, links, m)
    if max(m["emission"]) > 0:
        emission = nodes.new("ShaderNodeEmission")
        emission.inputs["Color"].default_value = (*m["emission"], 1.0)
        geometry = nodes.new("ShaderNodeNewGeometry")
        front = nodes.new("ShaderNodeMath")
        front.operation = "SUBTRACT"
        front.inputs[0].default_value = 1.0
        links.new(geometry.outputs["Backfacing"], front.inputs[1])
        links.new(front.outputs["Value"], emission.inputs["Strength"])
        add = nodes.new("ShaderNodeAddShader")
        links.new(surface, add.inputs[0])
        links.new(emission.outputs["Emission"], add.inputs[1])
        surface = add.outputs["Shader"]
        mat.cycles.emission_sampling = "FRONT"
    links.new(surface, out.inputs["Surface"])
    return mat, bool(medium)


def read_obj_triangles(path):
    """The vertices (in Blender's frame) and rewound faces of an exported OBJ."""
    verts, faces = [], []
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                verts.append(to_blender([float(t) for t in parts[1:4]]))
            elif parts[0] == "f":
                a, b, c = (int(t.split("/")[0]) - 1 for t in parts[1:4])
                faces.append((a, c, b))  # the mirror turns the winding round
    return verts, faces


def _mesh_object(bpy, scene, name, verts, faces):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    scene.collection.objects.link(obj)
    return obj


def scene_from_export(bpy, desc, folder, width, height, threads, world=None, aperture_scale=1.0, plane_size=400.0):
    """Blender's scene of an rt-view export (module comment). `world` makes
    the Blender world to use (an environment map), called after Blender is
    reset; without it, the background colour.
    Exits with a message on what it cannot convert."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    if desc["camera"]["projection"] != "Perspective":
        sys.exit("only perspective cameras are converted")
    if desc.get("global_illumination") is None:
        sys.exit("the scene has no global_illumination: nothing to compare with a path tracer")
    converted = {m["name"]: material(bpy, m) for m in desc["materials"]}
    media = False
    coi = np.array(desc["camera"]["center_of_interest"], dtype=float)
    for i, o in enumerate(desc["objects"]):
        if o["kind"] == "Sphere":
            bpy.ops.mesh.primitive_uv_sphere_add(
                segments=256, ring_count=128, radius=o["radius"], location=to_blender(o["center"])
            )
            obj = bpy.context.active_object
            bpy.ops.object.shade_smooth()
        elif o["kind"] == "Triangles":
            if o.get("smooth"):
                sys.exit(f"object {i}: vertex normals are not exported")
            verts, faces = read_obj_triangles(os.path.join(folder, o["file"]))
            obj = _mesh_object(bpy, scene, f"object-{i}", verts, faces)
        elif o["kind"] == "Plane":
            n = np.array(o["normal"], dtype=float)
            centre = coi - (coi.dot(n) - o["d"]) * n
            helper = np.array([0.0, 0.0, 1.0] if abs(n[1]) > 0.9 or abs(n[0]) > 0.9 else [0.0, 1.0, 0.0])
            u = np.cross(n, helper)
            u /= np.linalg.norm(u)
            v = np.cross(n, u)
            s = plane_size / 2
            corners = [centre + s * (a * u + b * v) for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
            verts = [to_blender(c.tolist()) for c in corners]
            # Wound so that Blender's normal (after the mirror) is rt-view's n.
            faces = [(0, 1, 2, 3)]
            obj = _mesh_object(bpy, scene, f"object-{i}", verts, faces)
            normal = obj.data.polygons[0].normal
            if np.dot(np.array(normal), np.array(to_blender(n.tolist()))) < 0:
                obj.data.polygons[0].flip()
        else:
            sys.exit(f"object {i}: a {o['kind']} is not converted")
        mat, medium = converted[o["material"]]
        media = media or medium
        obj.data.materials.append(mat)
    for i, light in enumerate(desc["lights"]):
        if not light["shadows"]:
            sys.exit(f"lights[{i}] has shadows: false, which Cycles cannot render")
        power = light["power"]
        peak = max(power)
        if light["kind"] == "Point":
            data = bpy.data.lights.new(f"light-{i}", "POINT")
            data.energy = 4 * math.pi * peak
            data.shadow_soft_size = 0.0
            location = to_blender(light["position"])
        elif light["kind"] == "Directional":
            data = bpy.data.lights.new(f"light-{i}", "SUN")
            data.energy = peak
            data.angle = 0.0
            location = (0.0, 0.0, 0.0)
        else:
            sys.exit(f"lights[{i}] is a {light['kind']} light: not converted")
        data.color = [p / peak if peak > 0 else 0.0 for p in power]
        obj = bpy.data.objects.new(f"light-{i}", data)
        obj.location = location
        if light["kind"] == "Directional":
            from mathutils import Vector

            obj.rotation_euler = Vector((0, 0, -1)).rotation_difference(Vector(to_blender(light["direction"]))).to_euler()
        scene.collection.objects.link(obj)
    if world is None:
        if desc.get("environment"):
            sys.exit("the scene has an environment map: not converted here (bench/cycles_env_compare.py converts one)")
        scene.world = uniform_world(bpy, desc["background"])
    else:
        scene.world = world()
    camera(bpy, desc["camera"], scene, aperture_scale)
    settings(scene, width, height, threads, desc["global_illumination"]["max_bounces"] - 1)
    if media:
        c = scene.cycles
        c.volume_bounces = 1024
        c.max_bounces = 1024
    return scene


def render(bpy, scene, out, spp, seed):
    """Renders `spp` samples with `seed` into the EXR `out`; returns the
    seconds `bpy.ops.render.render` took (scene sync, render, denoising if
    on, and the 32-bit EXR write)."""
    import time

    scene.cycles.samples = spp
    scene.cycles.seed = seed
    scene.render.filepath = os.path.abspath(out)
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    return time.perf_counter() - start


def read_exr(bpy, path):
    """Linear RGB of an OpenEXR file, rows top to bottom, as float64."""
    img = bpy.data.images.load(os.path.abspath(path), check_existing=False)
    w, h = img.size
    pixels = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(pixels)
    bpy.data.images.remove(img)
    return pixels.reshape(h, w, 4)[::-1, :, :3].astype(np.float64)


def write_png(bpy, path, rgb8):
    """An 8-bit PNG of rows top to bottom."""
    h, w, _ = rgb8.shape
    img = bpy.data.images.new(os.path.basename(path), w, h, alpha=False)
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[..., :3] = rgb8[::-1] / 255.0
    img.pixels.foreach_set(rgba.ravel())
    img.filepath_raw = os.path.abspath(path)
    img.file_format = "PNG"
    img.save()
    bpy.data.images.remove(img)
