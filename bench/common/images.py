"""Image statistics the bench scripts share: block means and their
agreement test, RMSE, SSIM and sRGB encoding, all on H×W×3 numpy arrays of
linear radiance, rows top to bottom."""

import math

import numpy as np

LUMINANCE = np.array([0.2126, 0.7152, 0.0722])  # Rec. 709 weights


def block_means(image, block):
    """The mean of each `block`×`block` block of pixels (a partial block at
    the right or bottom edge is left out)."""
    h, w, _ = image.shape
    bh, bw = h // block, w // block
    cut = image[: bh * block, : bw * block]
    return cut.reshape(bh, block, bw, block, 3).mean(axis=(1, 3))


def agreement(a, b, block, z, rel):
    """Block agreement of two lists of independent images: (a boolean map
    of the blocks that agree in every channel, whole-image means a/b). A
    block agrees when |ā − b̄| ≤ z·√(se_a² + se_b²) + rel·max(|ā|, |b̄|),
    the standard errors from the spread of the images' block means."""
    ba = np.stack([block_means(im, block) for im in a])
    bb = np.stack([block_means(im, block) for im in b])
    n = len(a)
    ma, mb = ba.mean(0), bb.mean(0)
    sa, sb = ba.std(0, ddof=1) / math.sqrt(n), bb.std(0, ddof=1) / math.sqrt(n)
    agree = (np.abs(ma - mb) <= z * np.sqrt(sa**2 + sb**2) + rel * np.maximum(np.abs(ma), np.abs(mb))).all(axis=2)
    ratio = np.mean(a, axis=0).mean(axis=(0, 1)) / np.maximum(np.mean(b, axis=0).mean(axis=(0, 1)), 1e-30)
    return agree, ratio


def block_z(mean_a, se_a, mean_b, se_b):
    """z-scores of two renderers' block means, and a line describing their
    spread: (|z| map, one value per block channel; the description). A
    block channel with no noise in either (bare background: the same value
    in every batch of both) has no z — a rounding difference over an error
    of 0 would be infinite — so it gets z = 0 in the map and is left out of
    the median, 99th percentile and maximum, and counted apart with its
    largest relative difference."""
    se = np.sqrt(se_a**2 + se_b**2)
    noisy = se > 0
    z = np.where(noisy, (mean_a - mean_b) / np.where(noisy, se, 1.0), 0.0)
    line = "|z| of the block means (channels with noise): "
    if noisy.any():
        line += (
            f"median {np.median(np.abs(z[noisy])):.2f}, 99th percentile"
            f" {np.percentile(np.abs(z[noisy]), 99):.2f}, max {np.abs(z[noisy]).max():.2f}"
        )
    else:
        line += "none"
    quiet = np.abs(mean_a - mean_b)[~noisy] / np.maximum(np.abs(mean_b[~noisy]), 1e-30)
    if quiet.size:
        line += (
            f"; {quiet.size} block channels without noise in either (bare background),"
            f" largest relative difference {quiet.max():.1e}"
        )
    return z, line


def srgb(image):
    """8-bit sRGB of linear `image` clamped to [0, 1]."""
    x = np.clip(image, 0, 1)
    x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return (x * 255 + 0.5).astype(np.uint8)


def srgb_luminance(rgb):
    """Luminance (Rec. 709 weights) of `rgb` clamped to [0, 1], sRGB-encoded."""
    y = np.clip(rgb, 0, 1) @ LUMINANCE
    return np.where(y <= 0.0031308, 12.92 * y, 1.055 * np.power(y, 1 / 2.4) - 0.055)


def gaussian_filter(image, sigma=1.5, radius=5):
    """`image` convolved with a normalised Gaussian, separably; edges reflected."""
    x = np.arange(-radius, radius + 1)
    k = np.exp(-(x * x) / (2 * sigma * sigma))
    k /= k.sum()
    padded = np.pad(image, radius, mode="reflect")
    rows = sum(k[i] * padded[:, i : i + image.shape[1]] for i in range(len(k)))
    return sum(k[i] * rows[i : i + image.shape[0], :] for i in range(len(k)))


def ssim(a, b):
    """Mean SSIM of two one-channel images in [0, 1] (Wang et al. 2004,
    "Image quality assessment: from error visibility to structural
    similarity", IEEE TIP 13(4), eq. 13): 11×11 Gaussian window of σ = 1.5,
    K1 = 0.01, K2 = 0.03."""
    c1, c2 = 0.01**2, 0.03**2
    mu_a, mu_b = gaussian_filter(a), gaussian_filter(b)
    var_a = gaussian_filter(a * a) - mu_a**2
    var_b = gaussian_filter(b * b) - mu_b**2
    cov = gaussian_filter(a * b) - mu_a * mu_b
    s = ((2 * mu_a * mu_b + c1) * (2 * cov + c2)) / ((mu_a**2 + mu_b**2 + c1) * (var_a + var_b + c2))
    return float(s.mean())


def rmse_clamped(a, b):
    """RMSE of linear radiance clamped to [0, 1] (as a display shows it),
    all pixels and channels."""
    return float(np.sqrt(np.mean((np.clip(a, 0, 1) - np.clip(b, 0, 1)) ** 2)))
