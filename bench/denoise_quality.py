#!/usr/bin/env python3
"""How much Open Image Denoise gains on a scene: RMSE and SSIM of noisy and
denoised rt-view renders against a high-sample rt-view reference.

    pip install mitsuba numpy            (mitsuba only reads the EXR layers)
    scripts/get_oidn.sh
    cargo build --release -p rt-view
    python3 bench/denoise_quality.py scenes/cornell_box.ron --spp 4,16,64

The reference is rendered with `--reference-spp` samples and seed 1 (so its
noise is independent of the test images', seed 0). Each test image is one
`rt-view render --denoise` to EXR, which holds the denoised colour (`R, G,
B`) and the noisy one (`noisy.R, …`) of the same samples, so both are judged
on the same render. RMSE: linear radiance clamped to [0, 1] (as a display
shows it; unclamped, the light's radiance of 17 would outweigh the room),
all pixels and channels. SSIM: Wang et al. 2004 ("Image quality assessment:
from error visibility to structural similarity", IEEE TIP 13(4)), 11×11
Gaussian window with σ = 1.5, K1 = 0.01, K2 = 0.03, on the sRGB-encoded
luminance in [0, 1]. The reference's own noise sets a floor under the
RMSE (printed). Times are the command's own: the render, and OIDN's.
"""

import argparse
import os
import re
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from common.images import rmse_clamped as rmse  # noqa: E402
from common.images import srgb_luminance, ssim  # noqa: E402


def read_layers(mi, path):
    """The EXR at `path` as {layer name: H×W×C array} ('' for R, G, B)."""
    bitmap = mi.Bitmap(path)
    layers = {}
    for name, b in bitmap.split():
        array = np.array(b, dtype=np.float64)
        fields = [b.struct_()[i].name for i in range(array.shape[2])]
        layers[name] = (array, fields)
    root, fields = layers["<root>"]
    out = {"": np.stack([root[:, :, fields.index(c)] for c in "RGB"], axis=2)}
    if "noisy" in layers:
        out["noisy"] = layers["noisy"][0][:, :, :3]
    return out


def render(rt_view, scene, out, spp, size, seed, denoise):
    args = [rt_view, "render", scene, "-o", out, "--spp", str(spp), "--seed", str(seed)]
    args += ["--width", str(size[0]), "--height", str(size[1])]
    if denoise:
        args.append("--denoise")
    done = subprocess.run(args, capture_output=True, text=True, check=True)
    took = float(re.search(r"spp\) in ([0-9.]+) s", done.stderr).group(1))
    oidn = re.search(r"denoised with OIDN in ([0-9.]+) s", done.stderr)
    if denoise and not oidn:
        sys.exit(f"not denoised:\n{done.stderr}")
    return took, float(oidn.group(1)) if oidn else None


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("scene")
    p.add_argument("--spp", default="4,16,64", help="sample counts, comma-separated")
    p.add_argument("--reference-spp", type=int, default=1024)
    p.add_argument("--size", default="128x128", help="image size WxH")
    p.add_argument("--rt-view", default="target/release/rt-view")
    p.add_argument("--out", default="denoise-out", help="folder for the images")
    a = p.parse_args()
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    size = tuple(int(n) for n in a.size.split("x"))
    os.makedirs(a.out, exist_ok=True)
    reference_path = os.path.join(a.out, f"reference-{a.reference_spp}.exr")
    if not os.path.exists(reference_path):
        render(a.rt_view, a.scene, reference_path, a.reference_spp, size, 1, False)
    reference = read_layers(mi, reference_path)[""]
    luminance = srgb_luminance(reference)
    print(f"{a.scene} at {size[0]}x{size[1]}, reference {a.reference_spp} spp (seed 1)")
    print("| spp | render s | OIDN s | RMSE noisy | RMSE denoised | SSIM noisy | SSIM denoised |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for spp in [int(n) for n in a.spp.split(",")]:
        path = os.path.join(a.out, f"{spp}spp.exr")
        took, oidn = render(a.rt_view, a.scene, path, spp, size, 0, True)
        layers = read_layers(mi, path)
        noisy, clean = layers["noisy"], layers[""]
        for name, image in [("noisy", noisy), ("denoised", clean)]:
            mi.Bitmap(np.clip(image, 0, 1).astype(np.float32)).convert(
                mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, True
            ).write(os.path.join(a.out, f"{spp}spp-{name}.png"))
        print(
            f"| {spp} | {took:.2f} | {oidn:.3f} | {rmse(noisy, reference):.4f} | {rmse(clean, reference):.4f} "
            f"| {ssim(srgb_luminance(noisy), luminance):.4f} | {ssim(srgb_luminance(clean), luminance):.4f} |"
        )


if __name__ == "__main__":
    main()
