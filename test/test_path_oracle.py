"""rtcl's path tracer against an independent renderer, Mitsuba 3 (issue 40), and
against the white furnace's analytic answer (docs/oracle.md).

Each scene under test/oracle/ (and scenes/cornell.json) has a reference under
test/oracle/refs/, rendered by Mitsuba 3 (`tools/build/mitsuba_ref.py`, many samples a
pixel, the command in each file's meta) and committed as data: these tests need
no Mitsuba. rtcl renders the scene at a moderate number of samples, small, to a
PFM, and the means of its 8x8-pixel blocks are compared with the reference's,
channel by channel, within

    tol = Z * sqrt(s^2 / (64 n) + s^2 / (64 N)) + REL * |ref| + ABS

where s is the standard deviation of one sample's contribution to the block
(the reference measured it from the spread of its independent batches), n and
N rtcl's and the reference's samples a pixel: Z standard errors of the Monte
Carlo noise of both images (an independent sampler's: rtcl's Sobol' points do
better on most blocks, 3-5 times worse on a smooth glass ball in a furnace,
whose blocks then reach 9 standard errors, which REL covers: docs/oracle.md,
"Agreement"), plus REL of the value for what the two renderers may
rightly differ in (float against Mitsuba's float, the sphere and triangle
intersection epsilons) and ABS for blocks that are almost black.  The image's
mean is compared the same way, with the noise of all its blocks.

make test runs the camera check, the Cornell box (at its depth and at depth
1) and the analytic furnace (about 8 s of CPU together, cold, with PoCL's and
rtcl's program caches off); the other scenes, the wavefront kernel and the
CPU reference are marked slow (make test-long).
"""
import hashlib
import json
import math
import os
import pathlib
import subprocess

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
ORACLE = ROOT / "test" / "oracle"
REFS = ORACLE / "refs"
BLOCK = 8

Z = 5.0      # standard errors of the combined noise
REL = 0.01   # of the reference value: what two correct renderers may differ in
ABS = 2e-3   # absolute, for blocks near black
# The image's mean, a sum over 64 blocks, is closer to Gaussian and its own
# noise smaller: 4 standard errors and half a per cent (a 2 % error in all of
# the image fails; docs/oracle.md, "Tolerances").
Z_MEAN = 4.0
REL_MEAN = 0.005


def read_pfm(path):
    """A PFM image as an H x W x 3 float32 array, rows from the top."""
    data = pathlib.Path(path).read_bytes()
    kind, size, scale, body = data.split(b"\n", 3)
    assert kind == b"PF", kind
    width, height = map(int, size.split())
    order = "<f4" if float(scale) < 0 else ">f4"
    return np.frombuffer(body, dtype=order, count=width * height * 3).reshape(
        height, width, 3)[::-1]


def load_ref(name):
    with np.load(REFS / f"{name}.npz", allow_pickle=False) as ref:
        return ref["image"], ref["block_sample_std"], json.loads(str(ref["meta"]))


def render(tmp_path, scene, width, height, spp, *extra, optimised=True):
    """rtcl's image of scene. A path-traced render is built with LLVM's
    optimisations even under make test's POCL_EXTRA_BUILD_FLAGS=-cl-opt-disable:
    its render is long and its build short, the other way round from the
    suite's Whitted images (the Cornell box at 64x64 and 256 samples, cold, PoCL's
    and rtcl's caches off: 6.6 s of CPU unoptimised, 3.3 s optimised, build
    included)."""
    out = tmp_path / (pathlib.Path(scene).stem + ".pfm")
    env = dict(os.environ)
    if optimised:
        env.pop("POCL_EXTRA_BUILD_FLAGS", None)
    result = subprocess.run(
        [RTCL, str(scene), "--size", f"{width}x{height}", "--spp", str(spp), "-q",
         "-o", str(out), *extra], capture_output=True, text=True, timeout=600, env=env)
    assert result.returncode == 0, result.stderr
    return read_pfm(out)


def blocks(image):
    h, w, c = image.shape
    return image.reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK, c).astype(np.float64).mean(
        axis=(1, 3))


def compare(image, name, spp):
    """Asserts that image (rtcl at spp samples a pixel) matches reference name;
    returns the agreement in numbers (for the report)."""
    ref, sample_std, meta = load_ref(name)
    assert image.shape == ref.shape, (image.shape, ref.shape)
    ours, theirs = blocks(image), blocks(ref)
    n, big_n = BLOCK * BLOCK * spp, BLOCK * BLOCK * meta["spp"]
    sigma = sample_std.astype(np.float64) * math.sqrt(1 / n + 1 / big_n)
    tol = Z * sigma + REL * np.abs(theirs) + ABS
    diff = ours - theirs
    # z-scores where there is noise (not the sky seen directly, exact in both)
    noisy = sigma > 1e-4 * np.abs(theirs) + 1e-7
    z = np.where(noisy, diff / np.where(noisy, sigma, 1), 0)
    # The whole image: its mean's noise is that of all blocks together.
    sigma_mean = np.sqrt(np.sum(sigma ** 2, axis=(0, 1))) / (sigma.shape[0] * sigma.shape[1])
    mean_diff = ours.mean(axis=(0, 1)) - theirs.mean(axis=(0, 1))
    mean_tol = Z_MEAN * sigma_mean + REL_MEAN * np.abs(theirs.mean(axis=(0, 1))) + ABS / 64
    worst = np.unravel_index(np.argmax(np.abs(diff) / tol), diff.shape)
    summary = (f"{name}: {diff.size} block channels, max |diff|/tol "
               f"{np.max(np.abs(diff) / tol):.2f} at block {worst[:2]} channel {worst[2]} "
               f"(rtcl {ours[worst]:.5f}, Mitsuba {theirs[worst]:.5f}, tol {tol[worst]:.5f}); "
               f"z-scores: rms {np.sqrt(np.mean(z ** 2)):.2f}, max |z| {np.max(np.abs(z)):.1f}; "
               f"the image mean differs by "
               f"{np.round((ours.mean(axis=(0, 1)) / theirs.mean(axis=(0, 1)) - 1) * 100, 2)} %, "
               f"|diff|/tol {np.round(np.abs(mean_diff) / mean_tol, 2)}")
    bad = np.argwhere(np.abs(diff) > tol)
    assert len(bad) == 0, summary + "; blocks outside: " + ", ".join(
        f"{tuple(b[:2])}/{b[2]} rtcl {ours[tuple(b)]:.4f} ref {theirs[tuple(b)]:.4f} "
        f"tol {tol[tuple(b)]:.4f}" for b in bad[:12])
    assert np.all(np.abs(mean_diff) <= mean_tol), summary
    print(summary)
    return summary


# ------------------------------------------------------------ the references

REFERENCES = sorted(p.stem for p in REFS.glob("*.npz"))


@pytest.mark.parametrize("name", REFERENCES)
def test_reference_is_of_the_scene_as_committed(name):
    """A scene, mesh or map changed after its reference was rendered fails
    here, with the command that renders the reference again."""
    _, _, meta = load_ref(name)
    for path, digest in meta["inputs"].items():
        data = (REFS / path).read_bytes()
        assert hashlib.sha256(data).hexdigest() == digest, (
            f"{path} changed since its reference was made; render it again: "
            f"{meta['command']}")


# --------------------------------------------------- camera, geometry, pixels

def whitted_flat(scene_path, tmp_path):
    """The scene with every material flat (ambient light 1 times the
    reflectance, nothing else) under the Whitted integrator: a pixel is then the
    coverage-weighted reflectance of what it sees, as Mitsuba's albedo AOV."""
    scene = json.loads(pathlib.Path(scene_path).read_text())
    scene.pop("integrator", None)
    for material in scene["materials"].values():
        colour = material.pop("bsdf")["reflectance"]
        material.pop("emission", None)
        material.update(color=colour, ambient=1, diffuse=0, specular=0)
    scene["ambient"] = [1, 1, 1]
    for mesh in scene["meshes"]:
        mesh["file"] = str(pathlib.Path(scene_path).parent.resolve() / mesh["file"])
    out = tmp_path / "flat.json"
    out.write_text(json.dumps(scene))
    return out


def test_cornell_camera_geometry_and_pixel_filter_match_mitsuba(tmp_path):
    """The same box seen from the same camera through the same pixels: rtcl's
    Whitted image of flat colours against Mitsuba's albedo AOV (needs no path
    tracer). A mirrored image, another field-of-view axis or a shifted pixel
    centre moves the walls' edges by pixels and fails by far."""
    image = render(tmp_path, whitted_flat(ROOT / "scenes" / "cornell.json", tmp_path),
                   64, 64, 64, optimised=False)
    ref, _, _ = load_ref("cornell_albedo")
    # Block means: a block's coverage of each colour, up to the edges' noise.
    assert np.max(np.abs(blocks(image) - blocks(ref))) < 0.01
    assert np.mean(np.abs(image - ref)) < 0.005
    assert np.max(np.abs(image - ref)) < 0.25  # an edge pixel's coverage noise at 64 spp


# ------------------------------------------------------------- path tracing

def test_cornell_box_matches_mitsuba(tmp_path):
    compare(render(tmp_path, ROOT / "scenes" / "cornell.json", 64, 64, 256), "cornell", 256)


@pytest.mark.slow
@pytest.mark.parametrize("kernel", ["wavefront", "reference"])
def test_cornell_box_matches_mitsuba_in_the_wavefront_kernel_and_the_cpu_reference(
        tmp_path, kernel):
    """The wavefront kernel (its own schedule of the path's bounces, within a
    tolerance of the others) and the CPU reference (double precision, its own
    code from RENDERING.md) against Mitsuba too; the other kernels give the
    default kernel's image byte for byte (test_kernels.c)."""
    compare(render(tmp_path, ROOT / "scenes" / "cornell.json", 64, 64, 256, "-k", kernel),
            "cornell", 256)


def test_cornell_box_at_max_depth_1_matches_mitsuba(tmp_path):
    """max_depth counts the bounces after the first hit (SCENE.md): 1 is
    direct light at two vertices, Mitsuba's max_depth 3. At depth 1 one bounce
    more or less changes the image by 9-17 %; at the box's depth 6, by 0.1-1 %,
    which the noise at 256 samples would hide."""
    compare(render(tmp_path, ORACLE / "cornell_depth1.json", 64, 64, 256),
            "cornell_depth1", 256)


# make test-long: make test keeps test_path.py's diffuse furnace.
@pytest.mark.slow
def test_white_furnace_diffuse_sphere_renders_its_albedo(tmp_path):
    """Analytic: a diffuse sphere of albedo rho under a uniform environment of
    radiance 1 reflects exactly rho (a convex object sees only the
    environment), and the environment seen directly is 1."""
    scene = ORACLE / "furnace_diffuse.json"
    doc = json.loads(scene.read_text())
    rho = np.array(doc["materials"]["grey"]["bsdf"]["reflectance"])
    spp = 64
    image = render(tmp_path, scene, 64, 64, spp).astype(np.float64)
    # The silhouette: a circle of radius tan(asin(r/d)) / tan(fov/2) half-heights.
    eye, radius = np.linalg.norm(doc["camera"]["eye"]), doc["spheres"][0]["radius"]
    r_px = 32 * math.tan(math.asin(radius / eye)) / math.tan(math.radians(doc["camera"]["fov"]) / 2)
    centre = np.arange(64) + 0.5 - 32
    dist = np.hypot(*np.meshgrid(centre, centre))
    inside = dist + math.sqrt(0.5) < r_px - 0.01
    outside = dist - math.sqrt(0.5) > r_px + 0.01
    assert np.all(image[outside] == 1.0), "the environment seen directly must be exactly 1"
    mean = image[inside].mean(axis=0)
    assert np.all(np.abs(mean - rho) < 0.005 * rho), (mean, rho)
    # Every pixel inside: within its noise (MIS of the environment's and the
    # BSDF's samples; 6 standard deviations of the per-pixel spread).
    spread = image[inside].std(axis=0)
    assert np.all(np.abs(image[inside] - rho) <= 6 * spread + 1e-6)
    compare(image.astype(np.float32), "furnace_diffuse", spp)


@pytest.mark.slow
def test_white_furnace_matches_mitsuba(tmp_path):
    """Four spheres under a uniform environment of 1: diffuse (0.9), smooth
    glass (renders 1 up to paths longer than max_depth), a white rough
    conductor (below 1: single-scattering GGX loses energy, the more the
    rougher) and rough glass."""
    compare(render(tmp_path, ORACLE / "furnace.json", 64, 64, 256), "furnace", 256)


@pytest.mark.slow
def test_glass_and_mirror_spheres_in_the_box_match_mitsuba(tmp_path):
    compare(render(tmp_path, ORACLE / "cornell_spheres.json", 64, 64, 1024),
            "cornell_spheres", 1024)


@pytest.mark.slow
def test_rough_conductor_and_dielectric_match_mitsuba(tmp_path):
    compare(render(tmp_path, ORACLE / "cornell_rough.json", 64, 64, 256),
            "cornell_rough", 256)


@pytest.mark.slow
def test_principled_materials_match_mitsuba(tmp_path):
    compare(render(tmp_path, ORACLE / "cornell_principled.json", 64, 64, 256),
            "cornell_principled", 256)


@pytest.mark.slow
def test_thin_transmitting_sheets_lit_from_behind_match_mitsuba(tmp_path):
    """Two single-sided sheets, rough glass and a principled one of
    transmission 1, between the camera and a lamp: light sampled through a
    surface (a transmitted light direction, its MIS weight against the
    BSDF's pdf on that side), which closed objects never need."""
    compare(render(tmp_path, ORACLE / "sheets.json", 64, 64, 256), "sheets", 256)


@pytest.mark.slow
def test_point_and_directional_lights_match_mitsuba(tmp_path):
    """SCENE.md's lights under "path": a point light's color is its intensity
    (falloff 1/r^2), a directional light's its irradiance; with a uniform sky."""
    compare(render(tmp_path, ORACLE / "lights.json", 64, 64, 256), "lights", 256)


@pytest.mark.slow
def test_environment_map_matches_mitsuba(tmp_path):
    """test/oracle/sky.hdr (tools/build/oracle_sky.py) turned by 30 degrees:
    its orientation, importance sampling by luminance and lookup."""
    compare(render(tmp_path, ORACLE / "env.json", 64, 64, 256), "env", 256)


@pytest.mark.slow
def test_textured_mtl_materials_match_mitsuba(tmp_path):
    """OBJ files' own MTL materials with a base colour texture (the floor of
    scenes/materials_path.json, its tiles.png repeated, and the crate): the
    texture coordinates, v's direction, the sRGB decoding, bilinear filtering
    and the repeat, against Mitsuba's bitmap of the same texels (issue 41)."""
    compare(render(tmp_path, ORACLE / "textured.json", 64, 64, 256), "textured", 256)
