"""rtcl-rays and rtcl-peer-compare --rays (issue 42): the rays both sides trace
are the ones docs/bvh.md documents (rtcl's camera; a cosine-distributed bounce
from the hash of the pixel; a shadow ray to the point light), made once into
files that both read, and rtcl's hits are the peer's on every ray. The peer is
TinyBVH (not part of the repository): the end-to-end test runs where its folder
is found ($RTCL_PEER, or shared/bench/tinybvh beside the checkout)."""
import os
import pathlib
import re
import struct
import subprocess
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
RTCL_RAYS = ROOT / "build" / "rtcl-rays"
PEER_PLACES = [os.environ.get("RTCL_PEER", ""), ROOT.parent / "shared/bench/tinybvh",
               ROOT.parent.parent / "shared/bench/tinybvh"]
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools.commands import peer_compare  # noqa: E402

PEER = next((pathlib.Path(p) for p in PEER_PLACES if p and (pathlib.Path(p) / "tiny_bvh.h").is_file()),
            None)
# The eye away from the world's origin: rtcl-rays takes the origins relative to
# it, as the device block holds every position (scene_from_eye).
SCENE = ('{"format": "rtcl-scene", "version": 2, "image": {"width": 8, "height": 8}, '
         '"camera": {"eye": [1, 2, 3], "look_at": [0, 0, -5]}, "max_depth": 0, "lights": [], '
         '"materials": {"m": {"color": [1, 1, 1]}}, '
         '"spheres": [{"center": [0, 0, -5], "radius": 1, "material": "m"}]}')


def read_rays(path):
    data = path.read_bytes()
    assert data[:8] == b"RTCLRAY1"
    count, flags = struct.unpack("<II", data[8:16])
    return np.frombuffer(data, dtype="<f4", offset=16).reshape(count, 8).astype(np.float64), flags


def lowbias32(x):
    x = np.asarray(x, dtype=np.uint64) & 0xFFFFFFFF
    x ^= x >> 16
    x = (x * 0x7FEB352D) & 0xFFFFFFFF
    x ^= x >> 15
    x = (x * 0x846CA68B) & 0xFFFFFFFF
    x ^= x >> 16
    return x


@pytest.mark.parametrize("content, message", [
    (b"NOTRAYS!" + bytes(8), "not a ray file"),
    (b"RTCLRAY1" + struct.pack("<II", 2, 0) + bytes(32), "48 bytes for 2 rays"),
])
def test_rtcl_rays_refuses_a_bad_ray_file_and_writes_nothing(tmp_path, content, message):
    if not RTCL_RAYS.is_file():
        pytest.skip("build/rtcl-rays is not built (make)")
    (tmp_path / "s.json").write_text(SCENE)
    (tmp_path / "r.rays").write_bytes(content)
    result = subprocess.run([RTCL_RAYS, tmp_path / "s.json", tmp_path / "r.rays",
                             tmp_path / "hits"], capture_output=True, text=True, timeout=60)
    assert result.returncode == 1
    assert message in result.stderr and result.stderr.count("\n") == 1, result.stderr
    assert not (tmp_path / "hits").exists()


def test_rtcl_rays_traces_the_rays_it_is_given(tmp_path):
    """A sphere of radius 1 at z = -5: a ray along -z from the world's origin
    meets it at t = 4 wherever the eye is, one along +x misses it, and a
    shadow ray stopped at t_max 3 before it finds nothing."""
    if not RTCL_RAYS.is_file():
        pytest.skip("build/rtcl-rays is not built (make)")
    (tmp_path / "s.json").write_text(SCENE)
    rays = [(0, 0, 0, 1e30, 0, 0, -1, 0), (0, 0, 0, 1e30, 1, 0, 0, 0)]
    for name, flags, extra in (("closest", 0, []), ("any", 1, [(0, 0, 0, 3, 0, 0, -1, 0)])):
        body = np.array(rays + extra, dtype="<f4").tobytes()
        (tmp_path / f"{name}.rays").write_bytes(b"RTCLRAY1" + struct.pack("<II", len(rays + extra), flags) + body)
        result = subprocess.run([RTCL_RAYS, "-r", "1", tmp_path / "s.json", tmp_path / f"{name}.rays",
                                 tmp_path / f"{name}.hits"], capture_output=True, text=True,
                                env={**os.environ, "POCL_WORK_GROUP_SPECIALIZATION": "0"},
                                timeout=300)
        assert result.returncode == 0, result.stderr
        hits = np.fromfile(tmp_path / f"{name}.hits", dtype="<f4").reshape(-1, 2)
        assert hits[0, 0] == pytest.approx(4, abs=1e-5) and hits[1, 0] == 0
        if extra:
            assert hits[2, 0] == 0
        assert re.search(r"hits 1;", result.stdout), result.stdout


def test_rtcl_rays_counts_the_work_per_ray(tmp_path):
    """-c: the counting build's node visits, leaf visits and tests per ray;
    one ray meets the lone sphere's leaf, the other misses the root's box."""
    if not RTCL_RAYS.is_file():
        pytest.skip("build/rtcl-rays is not built (make)")
    (tmp_path / "s.json").write_text(SCENE)
    body = np.array([(0, 0, 0, 1e30, 0, 0, -1, 0), (0, 0, 0, 1e30, 1, 0, 0, 0)], dtype="<f4")
    (tmp_path / "r.rays").write_bytes(b"RTCLRAY1" + struct.pack("<II", 2, 0) + body.tobytes())
    result = subprocess.run([RTCL_RAYS, "-c", tmp_path / "s.json", tmp_path / "r.rays",
                             tmp_path / "hits"], capture_output=True, text=True, timeout=300,
                            env={**os.environ, "POCL_WORK_GROUP_SPECIALIZATION": "0"})
    assert result.returncode == 0, result.stderr
    match = re.search(r"2 closest-hit rays counted \(2\); per ray: node visits ([\d.]+), "
                      r"leaf visits ([\d.]+), primitive tests ([\d.]+)", result.stdout)
    assert match, result.stdout
    nodes, leaves, tests = map(float, match.groups())
    assert nodes == 1 and leaves >= 0.5 and tests >= 0.5
    assert not (tmp_path / "hits").exists()


@pytest.mark.slow
@pytest.mark.skipif(PEER is None, reason="the peer's folder (TinyBVH) is not here; set RTCL_PEER")
def test_both_sides_trace_the_documented_rays_and_agree_on_every_hit(tmp_path):
    out = tmp_path / "out"
    result = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "peer_compare.py"), PEER, "--rays", "--cpu",
         "--rtcl", RTCL, "--meshes", "tetra:4", "--size", "40x24", "-r", "1", "-o", out],
        capture_output=True, text=True, cwd=tmp_path, timeout=900,
        env={**os.environ, "POCL_WORK_GROUP_SPECIALIZATION": "0"})
    assert result.returncode == 0, result.stderr
    folder = out / "rays" / "tetra-4"
    primary, _ = read_rays(folder / "primary.rays")
    bounce, _ = read_rays(folder / "bounce.rays")
    shadow, shadow_flags = read_rays(folder / "shadow.rays")
    width, height = 40, 24
    assert len(primary) == width * height and shadow_flags == 1

    # Primary rays: rtcl's camera, pixels in 8x4 tiles.
    scene = __import__("json").loads((out / "meshes" / "tetra-4-primary.json").read_text())
    camera = scene["camera"]
    eye, at = np.array(camera["eye"]), np.array(camera["look_at"])
    forward = (at - eye) / np.linalg.norm(at - eye)
    right = np.cross(forward, camera.get("up", [0, 1, 0]))
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    h = np.tan(np.radians(camera.get("fov", 45)) / 2)
    pixels = [(x, y) for ty in range(0, height, 4) for tx in range(0, width, 8)
              for y in range(ty, ty + 4) for x in range(tx, tx + 8)]
    xs, ys = np.array(pixels, dtype=np.float64).T
    d = (forward + ((2 * (xs + 0.5) / width - 1) * width / height * h)[:, None] * right
         + ((1 - 2 * (ys + 0.5) / height) * h)[:, None] * up)
    d /= np.linalg.norm(d, axis=1)[:, None]
    assert np.allclose(primary[:, :3], eye, atol=1e-6)
    assert np.allclose(primary[:, 4:7], d, atol=1e-5)

    # Bounce rays: one per primary hit, in order, from the hit point lifted
    # along the facing normal, cosine-distributed from the pixel's hash.
    tris = np.fromfile(out / "meshes" / "tetra-4.bin", dtype="<f4", offset=4).reshape(-1, 3, 4)[:, :, :3]
    hits = np.fromfile(folder / "primary.peer-hits", dtype="<f4").reshape(-1, 2)
    hit = hits[:, 0] > 0
    assert len(bounce) == len(shadow) == hit.sum() > 50
    prim = hits[hit, 1].view("<i4")
    v0, v1, v2 = (tris[prim, k].astype(np.float64) for k in range(3))
    n = np.cross(v1 - v0, v2 - v0)
    n /= np.linalg.norm(n, axis=1)[:, None]
    n *= np.where((n * primary[hit, 4:7]).sum(axis=1) > 0, -1, 1)[:, None]
    low, high = tris.reshape(-1, 3).min(axis=0), tris.reshape(-1, 3).max(axis=0)
    diagonal = np.linalg.norm(high - low)
    origin = primary[hit, :3] + hits[hit, 0:1] * primary[hit, 4:7] + 1e-5 * diagonal * n
    assert np.allclose(bounce[:, :3], origin, atol=1e-5 * diagonal)
    index = (ys * width + xs).astype(np.int64)[hit]
    u1 = (lowbias32(2 * index) >> 8) / 2.0**24
    u2 = (lowbias32(2 * index + 1) >> 8) / 2.0**24
    sign = np.copysign(1.0, n[:, 2])
    a = -1 / (sign + n[:, 2])
    b = n[:, 0] * n[:, 1] * a
    t1 = np.stack([1 + sign * n[:, 0] ** 2 * a, sign * b, -sign * n[:, 0]], axis=1)
    t2 = np.stack([b, sign + n[:, 1] ** 2 * a, -n[:, 1]], axis=1)
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    want = (r * np.cos(phi))[:, None] * t1 + (r * np.sin(phi))[:, None] * t2 + np.sqrt(1 - u1)[:, None] * n
    assert np.allclose(bounce[:, 4:7], want, atol=1e-4)
    assert np.all(bounce[:, 3] == np.float32(1e30))

    # Shadow rays: from the same origins to the light, t_max its distance.
    light = (low + high) / 2 + diagonal * np.array([0.3, 0.8, 0.5])
    toward = light - bounce[:, :3]
    distance = np.linalg.norm(toward, axis=1)
    assert np.allclose(shadow[:, :3], bounce[:, :3])
    assert np.allclose(shadow[:, 4:7], toward / distance[:, None], atol=1e-5)
    assert np.allclose(shadow[:, 3], distance, rtol=1e-5)

    # The two sides agree on every ray of every kind.
    rows = [line for line in (out / "rays.md").read_text().splitlines()
            if line.startswith("| tetra-4 |")]
    assert len(rows) == 3
    for row in rows:
        agreeing = row.strip("|").split("|")[-1].strip()
        same, count = re.fullmatch(r"([\d,]+) of ([\d,]+)", agreeing).groups()
        assert same == count, row


# rtcl --list-devices on the project's H100 machine: NVIDIA's platform first,
# PoCL's second; rtcl's default device there is the GPU.
GPU_PLATFORM = """Platform #0: NVIDIA CUDA
 `-- Device #0: NVIDIA H100 80GB HBM3 (GPU, 132 compute units, 48 KiB local, 81008 MiB global)
"""
GPU_THEN_POCL = GPU_PLATFORM + """Platform #1: Portable Computing Language
 `-- Device #0: cpu-sapphirerapids-Intel(R) Xeon(R) Platinum 8480+ (CPU, 16 compute units, 512 KiB local, 126000 MiB global)
"""


def test_cpu_runs_on_the_first_cpu_not_rtcls_default_gpu():
    """--cpu without -p: the first platform with a CPU, not rtcl's default
    device (the GPU, wherever there is one); with -p, that platform's CPU."""
    assert peer_compare.cpu_device(GPU_THEN_POCL) == (
        "1", "0", "cpu-sapphirerapids-Intel(R) Xeon(R) Platinum 8480+")
    assert peer_compare.cpu_device(GPU_THEN_POCL, "1")[:2] == ("1", "0")
    mixed = ("Platform #0: Some vendor\n |-- Device #0: gpu (GPU, 8 compute units, 1 KiB local, "
             "1 MiB global)\n `-- Device #1: cpu (CPU, 4 compute units, 1 KiB local, "
             "1 MiB global)\n")
    assert peer_compare.cpu_device(mixed) == ("0", "1", "cpu")


@pytest.mark.parametrize("listing, platform, message", [
    (GPU_PLATFORM, None, "--cpu: no CPU OpenCL device in rtcl --list-devices (install PoCL, "
                         "or leave out --cpu to time the GPU)"),
    (GPU_THEN_POCL, "0", "--cpu: platform 0 (NVIDIA CUDA) has no CPU device (GPU): "
                         "pass -p 1 (Portable Computing Language)"),
    (GPU_THEN_POCL, "2", "--cpu: -p 2: no such platform in rtcl --list-devices"),
], ids=["gpu-only", "p-names-the-gpu", "p-names-no-platform"])
def test_cpu_refuses_a_platform_without_a_cpu(listing, platform, message):
    with pytest.raises(peer_compare.Failure) as error:
        peer_compare.cpu_device(listing, platform)
    assert str(error.value) == message


@pytest.mark.parametrize("mode", [["--cpu"], ["--rays", "--cpu"], ["--cpu", "-p", "0"]])
def test_peer_compare_cpu_refuses_a_gpu_only_machine(tmp_path, capsys, mode):
    """On a machine whose only OpenCL device is a GPU (a fake rtcl that lists
    it), --cpu stops with one message before timing anything or writing a
    table; -p naming the GPU's platform likewise."""
    rtcl = tmp_path / "rtcl"
    rtcl.write_text("#!/bin/sh\ncat <<'EOF'\n" + GPU_PLATFORM + "EOF\n")
    rtcl.chmod(0o755)
    peer = tmp_path / "peer"
    peer.mkdir()
    for name in ("cside.cpp", "tiny_bvh.h", "ply2bin.py"):
        (peer / name).write_text("")
    (tmp_path / "rtcl-rays").write_text("#!/bin/sh\nexit 1\n")
    (tmp_path / "rtcl-rays").chmod(0o755)
    out = tmp_path / "out"
    assert peer_compare.main([str(peer), *mode, "--rtcl", str(rtcl), "--meshes", "tetra:1",
                              "-o", str(out)]) != 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    assert ("platform 0 (NVIDIA CUDA) has no CPU device (GPU): install PoCL" in err
            if "-p" in mode else "no CPU OpenCL device in rtcl --list-devices" in err), err
    assert not list(out.glob("*.md"))
