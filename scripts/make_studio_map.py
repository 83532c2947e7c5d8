#!/usr/bin/env python3
"""Writes a studio environment map: a dim room with a few bright softboxes.

    python3 scripts/make_studio_map.py OUT.hdr [WIDTH]

No photographs of real places are reachable from here, so the scenes' HDR
maps are made: this one by hand-placed rectangles, the sky by the renderer's
own sky model (`rt-view export` of a scene with `environment: Sky(...)`
writes it as `OUT.environment.hdr`). The map is equirectangular in
rt-view's convention (docs/scene-format.md): the top row is straight up,
the image's centre (u = 1/2) is straight ahead along +z, u = 1/4 is -x
(left), u = 3/4 is +x (right).

Radiance, linear RGB: a key light (u 0.62-0.74, v 0.18-0.36) of 40, a
cooler fill (u 0.22-0.3, v 0.3-0.45) of 6, a strip above (v 0.02-0.06) of
15, a grey ceiling fading to a darker floor. Written as flat (not
run-length encoded) RGBE, which every Radiance reader accepts, in pure
Python so the script needs nothing installed.
"""

import math
import os
import sys


def studio(u, v):
    """The map's radiance at image coordinates (u, v) in [0,1)^2."""
    if 0.62 <= u < 0.74 and 0.18 <= v < 0.36:
        return (40.0, 38.0, 34.0)  # key softbox, warm
    if 0.22 <= u < 0.30 and 0.30 <= v < 0.45:
        return (5.0, 5.6, 6.5)  # fill, cool
    if 0.02 <= v < 0.06 and 0.35 <= u < 0.65:
        return (15.0, 15.0, 15.0)  # strip light overhead
    if v < 0.5:
        g = 0.25 + 0.15 * math.cos(math.pi * v)  # ceiling and walls
        return (g, g, g * 1.02)
    g = 0.08 + 0.06 * (1.0 - v)  # floor
    return (g, g * 0.97, g * 0.93)


def rgbe(r, g, b):
    """Ward's shared-exponent encoding of one texel (Graphics Gems II, II.5)."""
    m = max(r, g, b)
    if m < 1e-32:
        return bytes((0, 0, 0, 0))
    mantissa, exponent = math.frexp(m)
    scale = mantissa * 256.0 / m
    return bytes((int(r * scale), int(g * scale), int(b * scale), exponent + 128))


def main():
    if len(sys.argv) < 2:
        print(__doc__.split("\n\n")[1])
        sys.exit(2)
    out = sys.argv[1]
    width = int(sys.argv[2]) if len(sys.argv) > 2 else 256
    height = width // 2
    body = bytearray()
    for j in range(height):
        for i in range(width):
            body += rgbe(*studio((i + 0.5) / width, (j + 0.5) / height))
    header = f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n".encode()
    with open(out + ".tmp", "wb") as f:
        f.write(header + bytes(body))
    os.replace(out + ".tmp", out)
    print(f"wrote {out} ({width}x{height})")


if __name__ == "__main__":
    main()
