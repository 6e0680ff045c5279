#!/usr/bin/env python3
"""Writes test/oracle/sky.hdr, the environment map of the oracle's test scene
test/oracle/env.json (docs/oracle.md): a 64 x 32 equirectangular sky in
rtcl's layout (RENDERING.md, "The environment": row 0 straight up, the middle
column looking along -z), a Radiance RGBE file of flat scanlines.

The sky: a blue zenith fading to a white horizon, a brown ground below it,
and a sun 40 degrees above the horizon towards -x (column 16), a Gaussian of
2 texels' width and peak 40 on top: bright enough that the map's importance
sampling matters, wide enough that rtcl's texel-constant map and Mitsuba's
bilinear one (tools/build/mitsuba_ref.py, `environment`) agree.

    python3 tools/build/oracle_sky.py        # needs numpy only
"""
import math
import pathlib

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
WIDTH, HEIGHT = 64, 32


def sky():
    v = (np.arange(HEIGHT) + 0.5) / HEIGHT            # texel centres
    theta = math.pi * v[:, None] * np.ones((1, WIDTH))
    elevation = math.pi / 2 - theta
    up = np.clip(np.sin(elevation), 0, 1)[..., None]
    zenith, horizon = np.array([0.25, 0.45, 1.0]), np.array([1.0, 1.0, 1.0])
    image = np.where(elevation[..., None] >= 0,
                     horizon + (zenith - horizon) * up ** 0.5,
                     np.array([0.35, 0.25, 0.15]) * np.ones_like(up))
    sun_row, sun_col = (0.5 - 40 / 180) * HEIGHT, 0.25 * WIDTH   # texel coordinates
    rows = (np.arange(HEIGHT) + 0.5)[:, None]
    cols = (np.arange(WIDTH) + 0.5)[None, :]
    sun = 40 * np.exp(-((rows - sun_row) ** 2 + (cols - sun_col) ** 2) / (2 * 2.0 ** 2))
    return image + (sun[..., None] * np.array([1.0, 0.9, 0.7]))


def rgbe(image):
    """RGBE bytes: the largest channel's exponent, each mantissa truncated."""
    top = image.max(axis=2)
    mantissa, exponent = np.frexp(top)
    scale = np.where(top > 1e-32, mantissa * 256 / np.where(top > 0, top, 1), 0)
    out = np.zeros(image.shape[:2] + (4,), np.uint8)
    out[..., :3] = np.floor(image * scale[..., None]).astype(np.uint8)
    out[..., 3] = np.where(top > 1e-32, exponent + 128, 0)
    return out


def main():
    pixels = rgbe(sky())
    header = f"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {HEIGHT} +X {WIDTH}\n".encode()
    (ROOT / "test" / "oracle" / "sky.hdr").write_bytes(header + pixels.tobytes())


if __name__ == "__main__":
    main()
