#!/usr/bin/env python3
"""Writes and renders the material figures of docs/scene-format.md.

    python3 scripts/material_figures.py [RT_VIEW] [--spp N] [--only NAME,NAME...]

One strip per parameter of the physically based material: six balls in a
row that differ in that parameter alone, everything else fixed, lit by the
studio environment map (scenes/studio.hdr) alone under the AgX view
transform. For each strip the script writes the scene
scenes/material_params/NAME.ron and renders it with rt-view to
docs/materials/NAME.png (560 x 100); then it renders the material
showcase, scenes/materials.ron, to docs/materials/showcase.png
(`--only showcase` for that alone). RT_VIEW is the rt-view binary
(default target/release/rt-view; build it first with
`cargo build --release -p rt-view`). The scenes are shipped, so one strip
can also be rendered by hand:
`rt-view render scenes/material_params/roughness.ron -o roughness.png`.

The strips that need texture coordinates (normal map, alpha cut-out,
texture transform) use a UV sphere mesh and small images that the script
also writes into scenes/material_params/: ball.obj (with its own
material, ball.mtl, which scenes/materials.ron shows), checker.png,
bumps_normal.png (a tangent-space normal map, glTF's convention, green up
the image) and stripes_alpha.png (opaque white with alpha falling from 1 to
0 across each of 8 stripes). Pure Python (the PNGs are written with zlib),
so the script needs nothing installed. Everything it writes is
deterministic: running it again gives the same scene files and textures,
and the same pictures from the same binary.
"""

import math
import os
import struct
import subprocess
import sys
import zlib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, "scenes", "material_params")
PICTURES = os.path.join(ROOT, "docs", "materials")

# The strip: six balls of radius 0.4, 1 apart along x, seen from far away
# (a narrow field of view, so the balls look alike) and a little above.
COUNT = 6
WIDTH, HEIGHT = 560, 100
SPP = 256

# Fixed values for every strip unless the strip varies them: an orange
# dielectric of medium roughness.
BASE = {"base_color": "(0.85, 0.25, 0.05)", "roughness": "0.35"}


def fmt(x):
    """A number as the scene file writes it: short, no trailing zeros."""
    s = f"{x:.4f}".rstrip("0").rstrip(".")
    return s if s not in ("", "-0") else "0"


def strip(name, caption, field, values, fixed=None, shape="sphere", spp=SPP, backdrop=False):
    """One strip: `field` takes each of `values` (already written as RON).
    `spp`: more for the strips of rough glass, whose caustics are noisy;
    `backdrop`: a grey bar behind the balls, to show what they let through."""
    return {
        "name": name,
        "caption": caption,
        "field": field,
        "values": values,
        "fixed": dict(BASE, **(fixed or {})),
        "shape": shape,
        "spp": spp,
        "backdrop": backdrop,
    }


def unit_steps():
    return [fmt(i / (COUNT - 1)) for i in range(COUNT)]


STRIPS = [
    strip("base_color", "base_color: red, orange, yellow, green, blue, white (roughness 0.35)",
          "base_color",
          ["(0.8, 0.1, 0.1)", "(0.85, 0.25, 0.05)", "(0.8, 0.7, 0.1)", "(0.15, 0.6, 0.2)",
           "(0.1, 0.2, 0.8)", "(0.9, 0.9, 0.9)"]),
    strip("metallic", "metallic: 0, 0.2, 0.4, 0.6, 0.8, 1 (base colour orange, roughness 0.2)",
          "metallic", unit_steps(), fixed={"roughness": "0.2"}),
    strip("roughness_metal", "roughness of a metal: 0, 0.2, 0.4, 0.6, 0.8, 1 (metallic 1, base colour gold)",
          "roughness", unit_steps(), fixed={"metallic": "1", "base_color": "(1.0, 0.78, 0.34)"}),
    strip("roughness", "roughness of a dielectric: 0, 0.2, 0.4, 0.6, 0.8, 1 (base colour orange)",
          "roughness", unit_steps()),
    strip("ior", "ior: 1.0, 1.2, 1.5, 2.0, 2.5, 3.0 (base colour dark blue, roughness 0.2)",
          "ior", ["1", "1.2", "1.5", "2", "2.5", "3"],
          fixed={"base_color": "(0.02, 0.04, 0.12)", "roughness": "0.2"}),
    strip("specular_factor", "specular_factor: 0, 0.2, 0.4, 0.6, 0.8, 1 (base colour dark blue, roughness 0.2)",
          "specular_factor", unit_steps(),
          fixed={"base_color": "(0.02, 0.04, 0.12)", "roughness": "0.2"}),
    strip("specular_color_factor",
          "specular_color_factor: white, red, yellow, green, cyan, blue (base colour dark grey, roughness 0.2, ior 2)",
          "specular_color_factor",
          ["(1, 1, 1)", "(1, 0.1, 0.1)", "(1, 0.9, 0.1)", "(0.1, 1, 0.1)", "(0.1, 0.9, 1)",
           "(0.1, 0.2, 1)"],
          fixed={"base_color": "(0.03, 0.03, 0.03)", "roughness": "0.2", "ior": "2"}),
    strip("transmission", "transmission: 0, 0.2, 0.4, 0.6, 0.8, 1 (base colour white, roughness 0)",
          "transmission", unit_steps(), fixed={"base_color": "(1, 1, 1)", "roughness": "0"}, spp=1024),
    strip("transmission_roughness",
          "roughness with transmission 1: 0, 0.1, 0.2, 0.3, 0.5, 0.8 (base colour white)",
          "roughness", ["0", "0.1", "0.2", "0.3", "0.5", "0.8"],
          fixed={"base_color": "(1, 1, 1)", "transmission": "1"}, spp=1024),
    strip("attenuation_distance",
          "attenuation_distance: none, 4, 2, 1, 0.5, 0.25 (attenuation_color (0.9, 0.45, 0.3), transmission 1, roughness 0; the balls are 0.8 across)",
          "attenuation_distance", [None, "4", "2", "1", "0.5", "0.25"],
          fixed={"base_color": "(1, 1, 1)", "roughness": "0", "transmission": "1",
                 "attenuation_color": "(0.9, 0.45, 0.3)"}, spp=1024),
    strip("clearcoat", "clearcoat: 0, 0.2, 0.4, 0.6, 0.8, 1 (base colour dark red, roughness 0.6, clearcoat_roughness 0.03)",
          "clearcoat", unit_steps(),
          fixed={"base_color": "(0.5, 0.03, 0.03)", "roughness": "0.6", "clearcoat_roughness": "0.03"}),
    strip("clearcoat_roughness",
          "clearcoat_roughness: 0, 0.2, 0.4, 0.6, 0.8, 1 (clearcoat 1, base colour dark red, roughness 0.6)",
          "clearcoat_roughness", unit_steps(),
          fixed={"base_color": "(0.5, 0.03, 0.03)", "roughness": "0.6", "clearcoat": "1"}),
    strip("emission_strength",
          "emission_strength: 0, 0.125, 0.25, 0.5, 1, 2 (emission (1, 0.35, 0.08), base colour dark grey)",
          "emission_strength", ["0", "0.125", "0.25", "0.5", "1", "2"],
          fixed={"base_color": "(0.1, 0.1, 0.1)", "emission": "(1, 0.35, 0.08)"}),
    strip("alpha_blend", "alpha with alpha_mode Blend: 0, 0.2, 0.4, 0.6, 0.8, 1 (base colour orange, a grey bar behind)",
          "alpha", unit_steps(), fixed={"alpha_mode": "Blend"}, backdrop=True),
    strip("alpha_cutoff",
          "alpha_cutoff with alpha_mode Mask: 0.05, 0.2, 0.4, 0.6, 0.8, 0.95, over a base colour texture whose alpha falls from 1 to 0 across each of 8 stripes (a grey bar behind)",
          "alpha_cutoff", ["0.05", "0.2", "0.4", "0.6", "0.8", "0.95"],
          fixed={"alpha_mode": "Mask", "base_color_texture": '"stripes_alpha.png"'}, shape="uv_sphere",
          backdrop=True),
    strip("normal_scale", "normal_scale: 0, 0.25, 0.5, 1, 2, -1 (a normal map of bumps; base colour orange, roughness 0.35)",
          "normal_scale", ["0", "0.25", "0.5", "1", "2", "-1"],
          fixed={"normal_texture": '"bumps_normal.png"'}, shape="uv_sphere"),
    strip("texture_scale",
          "a base colour texture's scale: (1, 1), (2, 2), (4, 4), (4, 1), rotation 45 at (4, 4), offset (0.0625, 0.125) at (4, 4) (KHR_texture_transform)",
          "base_color_texture",
          ['(file: "checker.png")',
           '(file: "checker.png", scale: (2, 2))',
           '(file: "checker.png", scale: (4, 4))',
           '(file: "checker.png", scale: (4, 1))',
           '(file: "checker.png", scale: (4, 4), rotation: 45)',
           '(file: "checker.png", scale: (4, 4), offset: (0.0625, 0.125))'],
          fixed={"base_color": "(1, 1, 1)", "roughness": "0.5"}, shape="uv_sphere"),
]


def scene_text(s):
    """The scene file of strip `s`."""
    lines = [
        f"// Material figure ({s['name']}): {s['caption']}.",
        "// Written by scripts/material_figures.py (edit it there, not here);",
        "// the picture is docs/materials/%s.png." % s["name"],
        "Scene(",
        "    camera: (position: (0, 6, -40), center_of_interest: (0, 0, 0), up: (0, 1, 0), fov_y: 1.55, near: 1),",
        f"    image: (width: {WIDTH}, height: {HEIGHT}),",
        f"    samples_per_pixel: {s['spp']},",
        "    color_space: Srgb,",
        "    view_transform: AgX,",
        "    exposure: -1,",
        '    environment: Map(file: "../studio.hdr", strength: 1, rotation: 20),',
        "    materials: {",
    ]
    for i, value in enumerate(s["values"]):
        fields = dict(s["fixed"])
        if value is not None:
            fields[s["field"]] = value
        body = ", ".join(f"{k}: {v}" for k, v in fields.items())
        lines.append(f'        "{i}": ({body}),')
    if s["backdrop"]:
        lines.append('        "backdrop": (base_color: (0.7, 0.7, 0.7), roughness: 0.8),')
    lines.append("    },")
    lines.append("    objects: [")
    for i in range(len(s["values"])):
        x = fmt(i - (len(s["values"]) - 1) / 2)
        if s["shape"] == "sphere":
            lines.append(f'        Sphere(center: ({x}, 0, 0), radius: 0.4, material: "{i}"),')
        else:
            lines.append(
                f'        Mesh(file: "ball.obj", scale: 0.4, translate: ({x}, 0, 0), material: "{i}"),')
    if s["backdrop"]:
        lines.append('        Aabb(min: (-3.2, -0.05, 0.6), max: (3.2, 0.05, 0.7), material: "backdrop"),')
    lines.append("    ],")
    lines.append("    effects: (global_illumination: (max_bounces: 12)),")
    lines.append(")")
    return "\n".join(lines) + "\n"


def uv_sphere(slices=48, stacks=24):
    """A unit UV sphere with positions, normals and texture coordinates: u
    goes once around (the seam at +z, the back seen from the strips'
    camera, u = 1/2 facing it and growing to the right), v from the south
    pole (0) to the north pole (1)."""
    out = ["# unit UV sphere with texture coordinates, written by scripts/material_figures.py"]
    out += ["mtllib ball.mtl", "usemtl tiles"]
    for j in range(stacks + 1):
        theta = math.pi * j / stacks  # from the north pole
        for i in range(slices + 1):
            phi = 2 * math.pi * i / slices
            x, y, z = -math.sin(theta) * math.sin(phi), math.cos(theta), math.sin(theta) * math.cos(phi)
            out.append(f"v {x:.5f} {y:.5f} {z:.5f}")
            out.append(f"vn {x:.5f} {y:.5f} {z:.5f}")
            out.append(f"vt {i / slices:.5f} {1 - j / stacks:.5f}")
    row = slices + 1
    for j in range(stacks):
        for i in range(slices):
            a, b = j * row + i + 1, j * row + i + 2
            c, d = a + row, b + row
            # (b - a) x (c - a) points outwards, as the normals do: the
            # winding MikkTSpace takes the tangent frame's handedness from.
            if j != 0:
                out.append(f"f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}")
            if j != stacks - 1:
                out.append(f"f {b}/{b}/{b} {d}/{d}/{d} {c}/{c}/{c}")
    return "\n".join(out) + "\n"


def png(width, height, channels, pixel):
    """An 8-bit PNG (RGB or RGBA) of `pixel(x, y)`, row 0 at the top."""
    raw = bytearray()
    for y in range(height):
        raw.append(0)
        for x in range(width):
            raw.extend(pixel(x, y))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    colour_type = 2 if channels == 3 else 6
    header = struct.pack(">IIBBBBB", width, height, 8, colour_type, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(bytes(raw), 9))
            + chunk(b"IEND", b""))


def checker(x, y):
    """8 x 4 squares of cream and dark teal on a 256 x 128 image."""
    return (235, 225, 200) if (x // 32 + y // 32) % 2 == 0 else (20, 90, 100)


def bumps_normal(x, y, width=256, height=128):
    """Round bumps, 16 around and 8 up, as tangent-space normals: the
    gradient of a height field h = cos²-shaped domes, encoded n·0.5 + 0.5."""
    cells_u, cells_v = 16, 8
    fu, fv = (x + 0.5) / width * cells_u, (y + 0.5) / height * cells_v
    du, dv = fu - math.floor(fu) - 0.5, fv - math.floor(fv) - 0.5
    r = math.hypot(du, dv)
    if r < 0.4:
        # h = cos²(πr/0.8): its slope along r, scaled to a steep dome.
        slope = -math.pi / 0.8 * math.sin(2 * math.pi * r / 0.8) * 0.25
        gx, gy = slope * du / max(r, 1e-6), slope * dv / max(r, 1e-6)
    else:
        gx = gy = 0.0
    # Image rows grow downwards, v upwards: the v slope flips sign.
    n = (-gx, gy, 1.0)
    length = math.sqrt(sum(c * c for c in n))
    return tuple(int(round((c / length * 0.5 + 0.5) * 255)) for c in n)


def stripes_alpha(x, y, width=256):
    """White, alpha falling from 255 to 0 across each of 8 vertical stripes."""
    t = (x % (width // 8) + 0.5) / (width // 8)
    return (255, 255, 255, int(round((1 - t) * 255)))


# The textured ball of scenes/materials.ron: an OBJ whose MTL material uses
# the PBR extension's fields, every one the loader reads (docs/models.md),
# and a few it names as unused (Ps, aniso), as exporters write them.
BALL_MTL = """# a physically based MTL material (the PBR extension), written by scripts/material_figures.py
newmtl tiles
Kd 1.0 1.0 1.0
map_Kd checker.png
Ni 1.5
Pr 1.0
map_Pr tiles_roughness.png
Pm 1.0
map_Pm tiles_metallic.png
Pc 0.3
Pcr 0.05
Ps 0.0
aniso 0.0
Ke 6.0 2.4 0.6
map_Ke seam_emissive.png
norm -bm 0.6 bumps_normal.png
"""


def tiles_metallic(x, y):
    """Grey: the checker's dark squares metal (255), the cream ones not (0)."""
    return (0, 0, 0) if (x // 32 + y // 32) % 2 == 0 else (255, 255, 255)


def tiles_roughness(x, y, height=128):
    """Grey: smooth (0.1) at the top of the image to rough (0.7) at the bottom."""
    g = int(round((0.1 + 0.6 * (y + 0.5) / height) * 255))
    return (g, g, g)


def seam_emissive(x, y, height=128):
    """Black but for a thin band along the equator (v = 1/2), where it glows."""
    return (255, 255, 255) if abs((y + 0.5) / height - 0.5) < 0.012 else (0, 0, 0)


def write(path, data):
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(path + ".tmp", mode) as f:
        f.write(data)
    os.replace(path + ".tmp", path)


def main(argv):
    rt_view = os.path.join(ROOT, "target", "release", "rt-view")
    spp, only = None, None
    args = iter(argv)
    for a in args:
        if a == "--spp":
            spp = next(args)
        elif a == "--only":
            only = next(args).split(",")
        else:
            rt_view = a
    os.makedirs(SCENES, exist_ok=True)
    os.makedirs(PICTURES, exist_ok=True)
    write(os.path.join(SCENES, "checker.png"), png(256, 128, 3, checker))
    write(os.path.join(SCENES, "bumps_normal.png"), png(256, 128, 3, bumps_normal))
    write(os.path.join(SCENES, "stripes_alpha.png"), png(256, 128, 4, lambda x, y: stripes_alpha(x, y)))
    write(os.path.join(SCENES, "ball.obj"), uv_sphere())
    write(os.path.join(SCENES, "ball.mtl"), BALL_MTL)
    write(os.path.join(SCENES, "tiles_metallic.png"), png(256, 128, 3, tiles_metallic))
    write(os.path.join(SCENES, "tiles_roughness.png"), png(256, 128, 3, tiles_roughness))
    write(os.path.join(SCENES, "seam_emissive.png"), png(256, 128, 3, seam_emissive))
    for s in STRIPS:
        write(os.path.join(SCENES, s["name"] + ".ron"), scene_text(s))
    for s in STRIPS:
        if only and s["name"] not in only:
            continue
        out = os.path.join(PICTURES, s["name"] + ".png")
        cmd = [rt_view, "render", os.path.join(SCENES, s["name"] + ".ron"), "-o", out]
        if spp:
            cmd += ["--spp", spp]
        print(" ".join(cmd), flush=True)
        subprocess.run(cmd, check=True, stderr=subprocess.DEVNULL)
    # The showcase, scenes/materials.ron (a scene written by hand).
    if not only or "showcase" in only:
        out = os.path.join(PICTURES, "showcase.png")
        cmd = [rt_view, "render", os.path.join(ROOT, "scenes", "materials.ron"), "-o", out]
        if spp:
            cmd += ["--spp", spp]
        print(" ".join(cmd), flush=True)
        subprocess.run(cmd, check=True, stderr=subprocess.DEVNULL)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
