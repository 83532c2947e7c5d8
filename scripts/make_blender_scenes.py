#!/usr/bin/env python3
"""Builds four small scenes in Blender and writes them with Blender's own
glTF 2.0 exporter, as an artist's files come: the models that
`scenes/cycles_*.ron` load and `bench/cycles_compare.py` renders with both
Blender Cycles and rt-view.

    python3.11 -m venv venv-bpy
    venv-bpy/bin/pip install bpy==5.0.1 numpy
    venv-bpy/bin/python scripts/make_blender_scenes.py [OUT_DIR]

OUT_DIR defaults to scenes/models. Each scene is made in a fresh, empty
Blender file (no start-up cube, light or camera), so the output depends on
this script and the Blender version only. Every file holds its camera and
its `KHR_lights_punctual` lights (exported in glTF's photometric units:
Blender's "Standard" lighting mode, a point light's watts become candela
through 683 lm/W and 4π sr, a sun's W/m² lux through 683 lm/W):

- `cycles_spheres.glb` — "MetalRoughSpheres": 5 × 5 spheres of one base
  colour (0.9, 0.55, 0.25), metallic 0 to 1 from the bottom row up,
  roughness 0 to 1 from left to right, on a grey Lambert floor, under a
  point light and a sun.
- `cycles_normal_map.glb` — a plane whose Principled BSDF takes a tangent-
  space normal map (a tile of round bumps, a grooved cross and a ridge,
  drawn here from a height field) through a Normal Map node, lit by a sun
  15° above the horizon.
- `cycles_suzanne.glb` — Suzanne (subdivided once, smooth, her UVs wrapped
  around her vertical axis) with a checker base-colour texture (orange and
  blue), a metallic-roughness texture (its blue channel, metallic, is 1 on
  the left half of the UV square, her left half as the camera sees her; its
  green channel, roughness, runs from 0.15 at the bottom of the UV square,
  her chin, to 0.8 at the top), wired as an artist would (Image Texture → Separate Color →
  Metallic and Roughness), and a normal map of small bumps through a Normal
  Map node; on a floor, under a point light and a sun.
- `cycles_glass.glb` — a rough glass sphere (transmission 1, roughness 0.3,
  IOR 1.5) resting on a floor and a rough glass cube beside it, 1 cm above
  the floor, before a wall, under a point light and a sun.

Textures are at most 256² texels and written into the .glb as PNG; each file
stays under 300 KB. Every triangle list's triangles are sorted after the
export (the exporter's order changes from run to run), so the files are the
same byte for byte each time the script runs. The Principled BSDFs keep Blender's defaults where the
scene does not set a value (IOR 1.5, specular IOR level 0.5), except the
floors, whose specular level is 0 (a plain Lambert surface, which glTF
writes as `KHR_materials_specular` with specularFactor 0).
"""

import json
import math
import os
import struct
import sys

import bpy
import numpy as np
from mathutils import Vector

# Blender's coordinates: +z up, the cameras look along +y. The exporter
# turns them into glTF's +y up (x, z, -y), and rt-view mirrors glTF's z, so a
# Blender point (x, y, z) is rt-view's (x, z, y).

BASE = (0.9, 0.55, 0.25)


def reset(width, height):
    """An empty Blender file with the render size the camera's aspect
    ratio is exported from."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.resolution_x = width
    scene.render.resolution_y = height
    scene.render.resolution_percentage = 100


def principled(name, base=(0.8, 0.8, 0.8), metallic=0.0, roughness=0.5, **inputs):
    """A material whose surface is one Principled BSDF; `inputs` sets any
    other input by its name with spaces as underscores."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*base, 1.0)
    bsdf.inputs["Metallic"].default_value = metallic
    bsdf.inputs["Roughness"].default_value = roughness
    for key, value in inputs.items():
        bsdf.inputs[key.replace("_", " ")].default_value = value
    return mat


def lambert(name, grey):
    """A floor: a Principled BSDF without specular reflection."""
    return principled(name, (grey, grey, grey), 0.0, 1.0, Specular_IOR_Level=0.0)


def add_object(name, mesh, material, location=(0, 0, 0)):
    obj = bpy.data.objects.new(name, mesh)
    obj.location = location
    bpy.context.scene.collection.objects.link(obj)
    if material is not None:
        obj.data.materials.append(material)
    return obj


def primitive(op, name, material, smooth=True, **kwargs):
    """An object made by a bpy.ops.mesh primitive operator, shaded smooth."""
    op(**kwargs)
    obj = bpy.context.active_object
    obj.name = name
    if smooth:
        for poly in obj.data.polygons:
            poly.use_smooth = True
    if material is not None:
        obj.data.materials.append(material)
    return obj


def floor(size, z, material):
    return primitive(bpy.ops.mesh.primitive_plane_add, "floor", material, smooth=False, size=size, location=(0, 0, z))


def camera(location, target, fov_y_degrees):
    """A perspective camera at `location` looking at `target`, +z up, with
    the given vertical field of view."""
    data = bpy.data.cameras.new("camera")
    data.sensor_fit = "VERTICAL"
    data.angle_y = math.radians(fov_y_degrees)
    data.clip_start = 0.1
    obj = add_object("camera", data, None, location)
    direction = Vector(target) - Vector(location)
    obj.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
    bpy.context.scene.camera = obj
    return obj


def point_light(name, location, watts, color=(1, 1, 1)):
    data = bpy.data.lights.new(name, "POINT")
    data.energy = watts
    data.color = color
    data.shadow_soft_size = 0.0
    return add_object(name, data, None, location)


def sun(name, toward, irradiance, color=(1, 1, 1)):
    """A sun shining along `toward` (its local -z) with `irradiance` W/m²."""
    data = bpy.data.lights.new(name, "SUN")
    data.energy = irradiance
    data.color = color
    data.angle = 0.0
    obj = add_object(name, data, None, (0, 0, 10))
    obj.rotation_euler = Vector(toward).to_track_quat("-Z", "Y").to_euler()
    return obj


def image(name, rgb, color_data):
    """A Blender image from an array of rows top to bottom, RGB in [0, 1]
    (8-bit when written): sRGB-encoded colour, or raw data (normal maps,
    metallic-roughness) with `color_data` False."""
    h, w, _ = rgb.shape
    img = bpy.data.images.new(name, w, h, alpha=False)
    # The colour space first: changing it reloads the image, which for a
    # generated one regenerates its blank pixels.
    img.colorspace_settings.name = "sRGB" if color_data else "Non-Color"
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[..., :3] = rgb[::-1]  # Blender's rows run bottom to top
    img.pixels.foreach_set(rgba.ravel())
    img.file_format = "PNG"
    img.pack()
    return img


def image_node(mat, img, location):
    node = mat.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = img
    node.interpolation = "Linear"
    node.location = location
    return node


def normal_map_node(mat, img, strength=1.0):
    """Image Texture (non-colour) → Normal Map (tangent space) → the
    Principled BSDF's Normal."""
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    tex = image_node(mat, img, (-700, -400))
    nm = nodes.new("ShaderNodeNormalMap")
    nm.space = "TANGENT"
    nm.inputs["Strength"].default_value = strength
    nm.location = (-300, -400)
    links.new(tex.outputs["Color"], nm.inputs["Color"])
    links.new(nm.outputs["Normal"], nodes["Principled BSDF"].inputs["Normal"])


def normals_from_height(height, depth):
    """A tangent-space normal map (rows top to bottom, +x right, +y up the
    image, Blender's and glTF's convention) of a height field of texels over
    a unit square, `depth` scaling the heights; encoded as (n + 1)/2."""
    n = height.shape[0]
    # Periodic central differences: the tile repeats without a seam.
    dx = (np.roll(height, -1, axis=1) - np.roll(height, 1, axis=1)) * n / 2
    dy_down = (np.roll(height, -1, axis=0) - np.roll(height, 1, axis=0)) * n / 2
    dy = -dy_down  # rows run down, +y runs up
    normal = np.stack([-depth * dx, -depth * dy, np.ones_like(height)], axis=-1)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    return (normal + 1) / 2


def canonical_triangle_order(path):
    """Sorts every triangle list's triangles in a .glb, in place: Blender's
    exporter writes the same triangles in an order that changes from run to
    run, and a file that changes with nothing in it changed is noise in
    the repository. Each triangle is rotated to start at its smallest index
    (its winding kept), then the triangles are sorted."""
    with open(path, "rb") as f:
        data = bytearray(f.read())
    json_length = struct.unpack_from("<I", data, 12)[0]
    doc = json.loads(data[20 : 20 + json_length])
    bin_start = 20 + json_length + 8
    done = set()
    for mesh in doc["meshes"]:
        for prim in mesh["primitives"]:
            index = prim.get("indices")
            if index is None or index in done or prim.get("mode", 4) != 4:
                continue
            done.add(index)
            acc = doc["accessors"][index]
            view = doc["bufferViews"][acc["bufferView"]]
            dtype = {5121: np.uint8, 5123: np.uint16, 5125: np.uint32}[acc["componentType"]]
            start = bin_start + view.get("byteOffset", 0) + acc.get("byteOffset", 0)
            size = acc["count"] * np.dtype(dtype).itemsize
            tris = np.frombuffer(bytes(data[start : start + size]), dtype=dtype).reshape(-1, 3)
            first = tris.argmin(axis=1)
            rotated = np.stack([tris[np.arange(len(tris)), (first + k) % 3] for k in range(3)], axis=1)
            rotated = rotated[np.lexsort(rotated.T[::-1])]
            data[start : start + size] = rotated.astype(dtype).tobytes()
    with open(path, "wb") as f:
        f.write(data)


def export(path, tangents=False):
    bpy.ops.export_scene.gltf(
        filepath=path,
        export_format="GLB",
        export_cameras=True,
        export_lights=True,
        export_import_convert_lighting_mode="SPEC",
        export_yup=True,
        export_apply=True,
        export_tangents=tangents,
        export_animations=False,
        export_image_format="AUTO",
    )
    canonical_triangle_order(path)
    print(f"{path}: {os.path.getsize(path) / 1024:.0f} KB")


def spheres(out):
    """(a) MetalRoughSpheres."""
    reset(256, 192)
    sphere_mesh = None
    for row, metallic in enumerate([0.0, 0.25, 0.5, 0.75, 1.0]):
        for col, roughness in enumerate([0.0, 0.25, 0.5, 0.75, 1.0]):
            mat = principled(f"m{metallic} r{roughness}", BASE, metallic, roughness)
            location = (-2.2 + 1.1 * col, 0.0, -2.2 + 1.1 * row)
            if sphere_mesh is None:
                obj = primitive(
                    bpy.ops.mesh.primitive_uv_sphere_add,
                    "sphere",
                    None,
                    segments=48,
                    ring_count=24,
                    radius=0.5,
                    location=location,
                )
                sphere_mesh = obj.data
                sphere_mesh.uv_layers.remove(sphere_mesh.uv_layers[0])
                sphere_mesh.materials.append(None)
            # Every sphere is the same mesh with a material of its own,
            # linked to the object (the exporter then shares the vertex data
            # between the spheres' primitives).
            obj = add_object(f"sphere m{metallic} r{roughness}", sphere_mesh, None, location)
            obj.material_slots[0].link = "OBJECT"
            obj.material_slots[0].material = mat
    bpy.data.objects.remove(bpy.data.objects["sphere"])
    floor(40, -2.8, lambert("floor", 0.5))
    camera((0, -14, 1.2), (0, 0, -0.3), 27)
    point_light("key", (-6, -10, 8), 5000)
    sun("sun", (0.5, 0.6, -1.0), 1.0, (1.0, 0.95, 0.9))
    export(os.path.join(out, "cycles_spheres.glb"))


def normal_map_plane(out):
    """(b) A normal-mapped plane under a grazing sun."""
    reset(192, 144)
    n = 256
    v, u = (np.mgrid[0:n, 0:n] + 0.5) / n  # rows down, columns right
    height = np.zeros((n, n))
    # Round bumps, 4 × 4 of them in the upper half of the tile.
    cu, cv = (u * 4) % 1 - 0.5, (v * 4) % 1 - 0.5
    r2 = cu**2 + cv**2
    bumps = np.where((v < 0.5) & (r2 < 0.16), np.sqrt(np.maximum(0.16 - r2, 0)), 0)
    # Horizontal grooves below, and one vertical ridge.
    grooves = np.where(v >= 0.5, 0.06 * np.cos(2 * math.pi * 8 * v) ** 2, 0)
    ridge = 0.12 * np.exp(-(((u - 0.75) / 0.04) ** 2)) * (v >= 0.5)
    height = bumps + grooves + ridge
    normals = normals_from_height(height, 0.6)
    mat = principled("bumpy", (0.7, 0.7, 0.7), 0.0, 0.4)
    normal_map_node(mat, image("bumps_normal", normals, False))
    primitive(bpy.ops.mesh.primitive_plane_add, "plane", mat, smooth=False, size=4)
    camera((0, -5.5, 4.0), (0, 0.2, 0), 40)
    sun("grazing sun", (-0.9, 0.5, -math.tan(math.radians(15)) * math.hypot(0.9, 0.5)), 3.0)
    export(os.path.join(out, "cycles_normal_map.glb"), tangents=True)


def wrap_around_uvs(mesh):
    """Replaces a mesh's UVs by a projection around its vertical axis: u
    runs once around (0.5 straight ahead along -y, the seam at the back, u
    below 0.5 on the model's -x side, the viewer's left), v from the lowest
    point (0) to the highest (1). The UV square's left half is then the
    model's left half."""
    co = np.array([v.co[:] for v in mesh.vertices])
    z0, z1 = co[:, 2].min(), co[:, 2].max()
    uv = mesh.uv_layers.active.data
    for poly in mesh.polygons:
        corners = []
        for li in poly.loop_indices:
            x, y, z = co[mesh.loops[li].vertex_index]
            corners.append([0.5 + math.atan2(x, -y) / (2 * math.pi), (z - z0) / (z1 - z0)])
        us = [c[0] for c in corners]
        if max(us) - min(us) > 0.5:  # a face across the seam: keep it whole
            for c in corners:
                c[0] += 1.0 if c[0] < 0.5 else 0.0
        for li, c in zip(poly.loop_indices, corners):
            uv[li].uv = c


def suzanne(out):
    """(c) Suzanne with base-colour, metallic-roughness and normal textures."""
    reset(192, 144)
    n = 256
    v, u = (np.mgrid[0:n, 0:n] + 0.5) / n  # image rows down, columns right
    checker = ((np.floor(u * 8) + np.floor(v * 8)) % 2)[..., None]
    orange, blue = np.array([1.0, 0.55, 0.1]), np.array([0.1, 0.3, 0.85])
    base = checker * orange + (1 - checker) * blue
    # Metallic-roughness: glTF's G is roughness, B metallic (R unused).
    mr = np.zeros((n, n, 3))
    mr[..., 1] = 0.8 - 0.65 * (1 - v)  # 0.8 at the top of the image, 0.15 at the bottom
    mr[..., 2] = (u < 0.5).astype(float)
    bumps = 0.5 + 0.5 * np.cos(2 * math.pi * 16 * u) * np.cos(2 * math.pi * 16 * v)
    normals = normals_from_height(bumps * 0.01, 1.0)

    mat = principled("pbr", (1, 1, 1), 0.0, 0.5)
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    bsdf = nodes["Principled BSDF"]
    links.new(image_node(mat, image("checker", base, True), (-700, 300)).outputs["Color"], bsdf.inputs["Base Color"])
    mr_tex = image_node(mat, image("metal_rough", mr, False), (-700, 0))
    sep = nodes.new("ShaderNodeSeparateColor")
    sep.location = (-350, 0)
    links.new(mr_tex.outputs["Color"], sep.inputs["Color"])
    links.new(sep.outputs["Green"], bsdf.inputs["Roughness"])
    links.new(sep.outputs["Blue"], bsdf.inputs["Metallic"])
    normal_map_node(mat, image("bumps", normals, False))

    monkey = primitive(bpy.ops.mesh.primitive_monkey_add, "Suzanne", mat, size=2.0, calc_uvs=True, location=(0, 0, 0))
    wrap_around_uvs(monkey.data)
    monkey.rotation_euler = (math.radians(-10), 0, math.radians(20))
    sub = monkey.modifiers.new("subdivision", "SUBSURF")
    sub.levels = sub.render_levels = 1
    floor(30, -1.0, lambert("floor", 0.45))
    camera((0, -6.0, 1.2), (0, 0, -0.1), 35)
    point_light("key", (-3, -4, 4), 1500, (1.0, 0.95, 0.9))
    sun("sun", (0.4, 0.8, -0.6), 1.5)
    export(os.path.join(out, "cycles_suzanne.glb"), tangents=True)


def glass(out):
    """(d) Rough glass on a floor."""
    reset(192, 144)
    mat = principled("rough glass", (1, 1, 1), 0.0, 0.3, Transmission_Weight=1.0, IOR=1.5)
    primitive(bpy.ops.mesh.primitive_uv_sphere_add, "glass sphere", mat, segments=64, ring_count=32, radius=0.8, location=(-0.6, 0, 0.8))
    # The cube floats 1 cm above the floor: a face lying in the floor's plane
    # would leave it to each renderer which of the two a ray meets first.
    cube = primitive(bpy.ops.mesh.primitive_cube_add, "glass cube", mat, smooth=False, size=0.9, location=(1.1, 0.6, 0.46))
    cube.rotation_euler = (0, 0, math.radians(30))
    floor(30, 0.0, lambert("floor", 0.6))
    wall = primitive(bpy.ops.mesh.primitive_plane_add, "wall", lambert("wall", 0.5), smooth=False, size=30, location=(0, 4, 0))
    wall.rotation_euler = (math.radians(90), 0, 0)
    camera((0.3, -5.5, 2.4), (0.2, 0.3, 0.6), 35)
    point_light("key", (2.5, -2.0, 4.0), 1500)
    sun("sun", (-0.5, 0.7, -0.8), 1.0, (1.0, 0.97, 0.92))
    export(os.path.join(out, "cycles_glass.glb"))


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "scenes", "models")
    out = os.path.abspath(out)
    os.makedirs(out, exist_ok=True)
    spheres(out)
    normal_map_plane(out)
    suzanne(out)
    glass(out)


if __name__ == "__main__":
    main()
