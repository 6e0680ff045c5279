#!/usr/bin/env python3
"""Writes scenes/models/sky.hdr, the environment map of scenes/studio_path.json
(issue 40): a procedural sky made here, so that it is free of any licence, as
a Radiance .hdr (RGBE, run-length encoded) of 256x128 texels, rows from the
top (+y) and the middle column along -z (docs/RENDERING.md, "The
environment"). A blue zenith fades to a pale horizon; below it a dim ground;
a small sun, 32 times as bright as the sky at its zenith, stands 40 degrees
high towards -x -z.

    /usr/bin/python3 tools/build/sky_hdr.py [OUT]
"""
import math
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
WIDTH, HEIGHT = 256, 128
SUN_ELEVATION, SUN_AZIMUTH = math.radians(40), math.radians(-135)  # azimuth from -z towards +x
SUN_RADIUS = math.radians(3)


def direction(u, v):
    """The map's direction of (u, v), rotate 0 (RENDERING.md)."""
    theta, phi = math.pi * v, 2 * math.pi * u
    return (-math.sin(theta) * math.sin(phi), math.cos(theta), math.sin(theta) * math.cos(phi))


def radiance(d):
    up = d[1]
    if up < 0:  # the ground: a dim grey-brown, darker straight down
        k = 0.25 + 0.15 * (1 + up)
        return (0.30 * k, 0.26 * k, 0.22 * k)
    horizon, zenith = (1.0, 1.0, 1.05), (0.25, 0.45, 0.95)
    t = up ** 0.5
    sky = tuple(h + (z - h) * t for h, z in zip(horizon, zenith))
    sun = (math.cos(SUN_ELEVATION) * math.sin(SUN_AZIMUTH), math.sin(SUN_ELEVATION),
           math.cos(SUN_ELEVATION) * math.cos(SUN_AZIMUTH))
    if sum(a * b for a, b in zip(d, sun)) > math.cos(SUN_RADIUS):
        return (32.0, 30.0, 26.0)
    return sky


def rgbe(c):
    m = max(c)
    if m < 1e-32:
        return bytes(4)
    mantissa, exponent = math.frexp(m)  # m = mantissa * 2^exponent, mantissa in [0.5, 1)
    scale = mantissa * 256.0 / m
    return bytes([int(c[0] * scale), int(c[1] * scale), int(c[2] * scale), exponent + 128])


def scanline(pixels):
    """One RLE scanline: the marker, then each channel in literal runs of 128."""
    out = bytearray([2, 2, WIDTH >> 8, WIDTH & 255])
    for ch in range(4):
        values = bytes(p[ch] for p in pixels)
        for at in range(0, WIDTH, 128):
            chunk = values[at:at + 128]
            out += bytes([len(chunk)]) + chunk
    return bytes(out)


def main():
    out = pathlib.Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "scenes" / "models" / "sky.hdr"
    data = bytearray(b"#?RADIANCE\n# made by tools/build/sky_hdr.py\nFORMAT=32-bit_rle_rgbe\n\n")
    data += b"-Y %d +X %d\n" % (HEIGHT, WIDTH)
    for k in range(HEIGHT):
        data += scanline([rgbe(radiance(direction((j + 0.5) / WIDTH, (k + 0.5) / HEIGHT)))
                          for j in range(WIDTH)])
    out.write_bytes(bytes(data))
    print(f"{out}: {WIDTH}x{HEIGHT}, {len(data)} bytes")


if __name__ == "__main__":
    main()
