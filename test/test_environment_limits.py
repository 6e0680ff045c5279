"""How much host memory an environment map takes while rendering (issue 39
finding 14; docs/SCENE.md, "environment"): like a texture's texels
(test_texture_limits.py), the map's device arrays, its texels with the scale
and its column CDFs, are written into the device's buffer a few rows at a time
from the scene's own texels, not packed into a host copy of the whole block
first."""
import json
import os
import pathlib
import resource
import subprocess

import pytest

import builds

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
ASAN = builds.built_with_asan(RTCL)  # AddressSanitizer reserves terabytes of address space


def flat_hdr(width, height):
    """A Radiance .hdr of width x height flat (not run-length encoded) pixels
    of radiance (0.5, 1, 0.25), a little brighter towards the right."""
    row = b"".join(bytes([64 + (j * 64 // width), 128, 32, 129]) for j in range(width))
    return (b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y %d +X %d\n" % (height, width)
            + row * height)


def scene(tmp_path):
    doc = {"format": "rtcl-scene", "version": 1, "integrator": "path", "max_depth": 1,
           "camera": {"eye": [0, 1, -3], "look_at": [0, 0, 0], "fov": 40},
           "environment": {"file": "sky.hdr", "scale": 2, "rotate": 30},
           "spheres": [{"center": [0, 0, 0], "radius": 1,
                        "material": {"bsdf": {"type": "diffuse",
                                              "reflectance": [0.5, 0.5, 0.5]}}}]}
    path = tmp_path / "env.json"
    path.write_text(json.dumps(doc))
    return path


def renders(path, out, mib):
    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (mib << 20, mib << 20))
    return subprocess.run([RTCL, path, "-o", out, "--size", "8x8"], cwd=ROOT,
                          capture_output=True, text=True, preexec_fn=limit, timeout=300)


def address_space_needed(path, out, low, high, step=16):
    """The least address space (MiB, to step) under which rtcl renders path:
    bisected between low (too little) and high (enough)."""
    assert renders(path, out, high).returncode == 0, f"rtcl does not render {path} in {high} MiB"
    while high - low > step:
        middle = (low + high) // 2
        low, high = (low, middle) if renders(path, out, middle).returncode == 0 \
            else (middle, high)
    return high


@pytest.mark.slow  # about 7 s of renders (a bisection): make test-long
@pytest.mark.skipif(ASAN, reason="AddressSanitizer reserves terabytes of address space")
def test_a_large_environment_map_is_held_twice_at_most_while_rendering(tmp_path):
    """A 4096x2048 map (32 MiB as RGBE; 96 MiB of float texels in the scene,
    160 MiB of device arrays: 16-byte texels and 4-byte column CDFs) renders
    within the address space the same scene needs with an 8x4 map plus the
    scene's texels and twice the device arrays: rtcl holds the arrays once,
    in the device buffer (PoCL's, on the host here). Before, the packed block
    held them a second time: it needed 516 MiB more than the small map, now
    356 (about 100 MiB of it in either is not the map's: the allocators'
    slack and PoCL's); its peak RSS went from 647 MB to 342 MB."""
    texels = 4096 * 2048 * 12 >> 20
    arrays = 4096 * 2048 * 20 >> 20
    path = scene(tmp_path)
    (tmp_path / "sky.hdr").write_bytes(flat_hdr(8, 4))
    small = address_space_needed(path, tmp_path / "o.ppm", 0, 4096)
    (tmp_path / "sky.hdr").write_bytes(flat_hdr(4096, 2048))
    # The large map's program first, with room to spare: it differs from the
    # small map's (whose map fits in __local memory), and building it under
    # the limit would measure PoCL's compiler (which crashed there, from an
    # empty cache), not the map's arrays.
    warm = renders(path, tmp_path / "o.ppm", 16384)
    assert warm.returncode == 0, warm.stderr
    limit = small + texels + 2 * arrays
    result = renders(path, tmp_path / "o.ppm", limit)
    assert result.returncode == 0, \
        f"in {limit} MiB ({small} + {texels} + 2 x {arrays}): {result.stderr}"
