"""--aov albedo,normal,depth and --denoise (docs/GUIDE.md, "Denoising and
auxiliary images"; docs/RENDERING.md, "Auxiliary images"): the auxiliary
images' values on scenes whose answer is known, the same bits from every
kernel, the files staged with the run's outputs, Open Image Denoise lowering
the error of a noisy image, and one clear message for every refusal."""
import json
import math
import os
import pathlib
import signal
import subprocess

import numpy as np
import pytest

from builds import built_with_asan

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
KINDS = ("albedo", "normal", "depth")


def rtcl(*args, env=None):
    return subprocess.run([RTCL, "-q", *args], capture_output=True, text=True, cwd=ROOT,
                          timeout=300, env={**os.environ, **(env or {})})


def read_pfm(path):
    """Rows top first, shape (height, width, 3)."""
    with open(path, "rb") as f:
        assert f.readline().strip() == b"PF"
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    return data.reshape(height, width, 3)[::-1]


def write_scene(tmp_path, spheres=(), planes=(), size=(33, 33), eye=(0, 0, -5), fov=40,
                lights=None, materials=None):
    doc = {
        "format": "rtcl-scene", "version": 1,
        "image": {"width": size[0], "height": size[1]},
        "camera": {"eye": list(eye), "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": fov},
        "background": [0.2, 0.25, 0.35], "max_depth": 2,
        "materials": materials or {"m": {"color": [0.3, 0.6, 0.9]}},
        "lights": lights if lights is not None else [{"position": [-3, 4, -6],
                                                      "color": [1, 1, 1]}],
        "spheres": list(spheres), "planes": list(planes),
    }
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(doc))
    return str(path)


def render_aov(tmp_path, scene, *args, name="out.png"):
    out = tmp_path / name
    result = rtcl(scene, "--aov", "albedo,normal,depth", "-o", str(out), *args)
    assert result.returncode == 0, result.stderr
    stem = str(out)[: -len(out.suffix)]
    return {k: read_pfm(f"{stem}.{k}.pfm") for k in KINDS}


def primary_directions(width, height, fov, eye=(0, 0, -5)):
    """RENDERING.md, "Camera and pixels": each pixel centre's unit direction."""
    f = -np.array(eye, float) / np.linalg.norm(eye)
    r = np.cross(f, [0, 1, 0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    h = math.tan(math.radians(fov) / 2)
    a = width / height
    x = (2 * (np.arange(width) + 0.5) / width - 1) * a * h
    y = (1 - 2 * (np.arange(height) + 0.5) / height) * h
    d = f + x[None, :, None] * r + y[:, None, None] * u
    return d / np.linalg.norm(d, axis=2, keepdims=True)


def test_albedo_is_the_material_colour_and_background(tmp_path):
    scene = write_scene(tmp_path, spheres=[{"center": [0, 0, 0], "radius": 1,
                                            "material": "m"}])
    aov = render_aov(tmp_path, scene, "--spp", "4")
    albedo = aov["albedo"]
    assert np.allclose(albedo[16, 16], [0.3, 0.6, 0.9], atol=1e-6)
    assert np.allclose(albedo[0, 0], [0.2, 0.25, 0.35], atol=1e-6)  # the background
    # Edge pixels mix the two in proportion to their samples.
    edge = albedo[16, :].tolist()
    assert any(0.2 < p[0] < 0.3 - 1e-3 for p in edge)


def test_normal_and_depth_of_a_sphere(tmp_path):
    scene = write_scene(tmp_path, spheres=[{"center": [0, 0, 0], "radius": 1,
                                            "material": "m"}])
    aov = render_aov(tmp_path, scene, "--spp", "1")
    normal, depth = aov["normal"], aov["depth"][:, :, 0]
    assert np.allclose(normal[16, 16], [0, 0, -1], atol=1e-6)
    assert depth[16, 16] == pytest.approx(4.0, abs=1e-5)
    hit = depth > 0
    assert 100 < hit.sum() < 33 * 33 - 100
    # Each hit's point, eye + depth · direction, lies on the sphere, and its
    # normal is the outward unit normal there (facing the camera).
    points = np.array([0, 0, -5]) + depth[..., None] * primary_directions(33, 33, 40)
    assert np.allclose(np.linalg.norm(points[hit], axis=1), 1, atol=1e-4)
    assert np.allclose(normal[hit], points[hit], atol=1e-3)
    assert np.all(normal[~hit] == 0) and np.all(depth[~hit] == 0)


def test_depth_of_a_plane_at_a_known_distance(tmp_path):
    scene = write_scene(tmp_path, size=(40, 30), fov=50,
                        planes=[{"point": [0, 0, 2], "normal": [0, 0, -1], "material": "m"}])
    aov = render_aov(tmp_path, scene, "--spp", "1")
    depth = aov["depth"][:, :, 0]
    forward = primary_directions(40, 30, 50)[..., 2]  # the ray's cosine to the normal
    assert np.allclose(depth * forward, 7.0, rtol=1e-5)
    assert np.allclose(aov["normal"], [0, 0, -1], atol=1e-6)


def assert_same_across_kernels(tmp_path, kernels, spp, scene=str(ROOT / "scenes" / "two_balls.json")):
    images = {}
    for kernel in kernels:
        out = tmp_path / f"{kernel}-{spp}.pfm"
        result = rtcl(scene, "--size", "24x16", "--spp", spp, "-k", kernel,
                      "--aov", "albedo,normal,depth", "-o", str(out))
        assert result.returncode == 0, result.stderr
        images[kernel] = [(tmp_path / f"{kernel}-{spp}.{k}.pfm").read_bytes() for k in KINDS]
    first = images[kernels[0]]
    for kernel, files in images.items():
        assert files == first, kernel


# make test-long: make test keeps the path-traced identity and denoise test.
@pytest.mark.slow
def test_auxiliary_images_identical_across_kernels(tmp_path):
    """One of each family: a persistent single-pass kernel, one work-item a
    pixel, and the wavefront's launches per bounce."""
    assert_same_across_kernels(tmp_path, ["dynamic", "naive", "wavefront"], "4")


def test_path_traced_auxiliary_images_identical_across_kernels(tmp_path):
    assert_same_across_kernels(tmp_path, ["dynamic", "wavefront"], "2",
                               scene=str(ROOT / "scenes" / "cornell.json"))


@pytest.mark.slow
@pytest.mark.parametrize("spp", ["1", "4"])
def test_auxiliary_images_identical_across_every_kernel(tmp_path, spp):
    assert_same_across_kernels(
        tmp_path, ["serial", "naive", "cyclic", "dynamic", "persistent", "wavefront"], spp)


def test_aov_files_named_beside_the_image_and_in_the_summary(tmp_path):
    scene = str(ROOT / "scenes" / "two_balls.json")
    result = subprocess.run([RTCL, scene, "--size", "16x12", "--aov", "depth,albedo",
                             "-o", str(tmp_path / "pic.png")], capture_output=True, text=True,
                            timeout=300)
    assert result.returncode == 0, result.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["pic.albedo.pfm", "pic.depth.pfm",
                                                         "pic.png"]
    assert "albedo" in result.stdout and "pic.depth.pfm" in result.stdout


def test_aov_clash_with_another_output_is_refused(tmp_path):
    result = rtcl("--size", "16x12", "--aov", "albedo", "-o", str(tmp_path / "a.png"),
                  "--stats", str(tmp_path / "a.albedo.pfm"))
    assert result.returncode == 2
    assert "--aov" in result.stderr and "--stats" in result.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("value", ["", "albedo,", "colour", "albedo,albedo", "normal depth"])
def test_bad_aov_list(value):
    result = rtcl("--aov", value)
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and "--aov" in result.stderr
    assert "albedo,normal,depth" in result.stderr


@pytest.mark.parametrize("option", [["--aov", "depth"], ["--denoise"]])
@pytest.mark.parametrize("other", [["-k", "reference"], ["--frames", "0:1"], ["--piece-rows", "4"],
                                   ["--devices", "0:0"]])
def test_options_the_auxiliary_pass_cannot_serve(tmp_path, option, other):
    result = rtcl(*option, *other, "-o", str(tmp_path / "x.png"))
    assert result.returncode == 2, result.stderr
    assert "--aov and --denoise" in result.stderr
    assert list(tmp_path.iterdir()) == []


def test_missing_library_message(tmp_path):
    result = rtcl("--size", "16x12", "--denoise", "-o", str(tmp_path / "x.png"),
                  env={"RTCL_OIDN_LIBRARY": str(tmp_path / "no-such-libOpenImageDenoise.so")})
    assert result.returncode == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    assert "cannot load Intel Open Image Denoise" in lines[0]
    assert "make deps" in lines[0] and "no-such-libOpenImageDenoise.so" in lines[0]
    assert list(tmp_path.iterdir()) == []


def test_a_library_without_oidn_is_refused(tmp_path):
    result = rtcl("--size", "16x12", "--denoise", "-o", str(tmp_path / "x.png"),
                  env={"RTCL_OIDN_LIBRARY": "libz.so.1"})
    assert result.returncode == 1
    assert "lacks oidnNewDevice" in result.stderr and "make deps" in result.stderr
    assert list(tmp_path.iterdir()) == []


def require_oidn(tmp_path):
    if built_with_asan(RTCL):
        # TBB, which OIDN runs on, dlopens its libtbbbind with RTLD_DEEPBIND,
        # which AddressSanitizer's runtime refuses (google/sanitizers#611).
        pytest.skip("Open Image Denoise's TBB cannot load under AddressSanitizer")
    probe = subprocess.run([RTCL, "--size", "8x8", "--denoise", "-o", str(tmp_path / "probe.pfm")],
                           capture_output=True, text=True, timeout=300)
    if probe.returncode and "cannot load Intel Open Image Denoise" in probe.stderr:
        pytest.skip("Open Image Denoise is not installed (`make deps` installs it): "
                    + probe.stderr.strip())
    assert probe.returncode == 0, probe.stderr
    assert "denoise: Open Image Denoise, RT filter with albedo and normal" in probe.stdout


# make test-long: make test keeps the path-traced identity and denoise test.
@pytest.mark.slow
def test_denoise_lowers_the_error_of_a_noisy_image(tmp_path):
    require_oidn(tmp_path)
    # Soft shadows of a large sphere light: noisy at a few samples per pixel.
    scene = write_scene(
        tmp_path, size=(48, 32), eye=(0, 3, -6), fov=50,
        lights=[{"position": [-2, 5, -1], "radius": 1.5, "color": [1, 1, 1]}],
        materials={"m": {"color": [0.8, 0.3, 0.2]}, "floor": {"color": [0.8, 0.8, 0.8]}},
        spheres=[{"center": [0, 1, 0], "radius": 1, "material": "m"}],
        planes=[{"point": [0, 0, 0], "normal": [0, 1, 0], "material": "floor"}])

    def image(name, *args):
        out = tmp_path / name
        result = rtcl(scene, "-o", str(out), *args)
        assert result.returncode == 0, result.stderr
        return read_pfm(out)

    truth = image("truth.pfm", "--spp", "256")
    noisy = image("noisy.pfm", "--spp", "4")
    denoised = image("denoised.pfm", "--spp", "4", "--denoise")

    def rmse(a):
        return float(np.sqrt(np.mean((a - truth) ** 2)))

    assert not np.array_equal(noisy, denoised)
    print("rmse noisy", rmse(noisy), "denoised", rmse(denoised))
    assert rmse(denoised) < 0.75 * rmse(noisy), (rmse(denoised), rmse(noisy))


def test_albedo_takes_the_image_sample_positions(tmp_path):
    """Lit by an ambient light of 1 alone (ka 1, no lights, max depth 0), a
    pixel's colour is the mean of its samples' base colours: the albedo, at the
    image's own sample positions, checker squares and edges included."""
    scene = json.loads((ROOT / "scenes" / "two_balls.json").read_text())
    scene.update(ambient=[1, 1, 1], lights=[], max_depth=0)
    for m in scene["materials"].values():
        m.update(reflect=0, transmit=0)
    path = tmp_path / "flat.json"
    path.write_text(json.dumps(scene))
    out = tmp_path / "flat.pfm"
    result = rtcl(str(path), "--size", "32x24", "--spp", "8", "--aov", "albedo", "-o", str(out))
    assert result.returncode == 0, result.stderr
    image, albedo = read_pfm(out), read_pfm(tmp_path / "flat.albedo.pfm")
    assert np.allclose(image, albedo, atol=1e-6)
    assert len(np.unique(albedo[..., 0])) > 6  # edges mixed, not only the materials


# make test-long: make test keeps the path-traced identity and denoise test.
@pytest.mark.slow
def test_albedo_of_textures_and_a_lens(tmp_path):
    """The studio (textured crate, cut-out trellis, a thin lens) lit by an
    ambient light of 1 alone: its image is its albedo, texture, cut-outs and
    the lens's sample positions included."""
    scene = json.loads((ROOT / "scenes" / "studio.json").read_text())
    scene.update(ambient=[1, 1, 1], lights=[], max_depth=0)
    for m in scene["materials"].values():
        m["ambient"] = 1
    for mesh in scene["meshes"]:
        mesh["file"] = str(ROOT / "scenes" / mesh["file"])
    path = tmp_path / "flat_studio.json"
    path.write_text(json.dumps(scene))
    out = tmp_path / "studio.pfm"
    result = rtcl(str(path), "--size", "64x40", "--spp", "4", "--aov", "albedo", "-o", str(out))
    assert result.returncode == 0, result.stderr
    assert np.allclose(read_pfm(out), read_pfm(tmp_path / "studio.albedo.pfm"), atol=1e-6)


def test_stats_time_the_auxiliary_pass_and_the_denoiser(tmp_path):
    stats = tmp_path / "s.json"
    result = rtcl("--size", "16x12", "--aov", "normal", "-o", str(tmp_path / "x.pfm"),
                  "--stats", str(stats))
    assert result.returncode == 0, result.stderr
    times = json.loads(stats.read_text())["time_breakdown_ms"]
    assert times["auxiliary_images"] > 0 and "denoise" not in times
    require_oidn(tmp_path)
    result = rtcl("--size", "16x12", "--denoise", "-o", str(tmp_path / "x.pfm"),
                  "--stats", str(stats))
    assert result.returncode == 0, result.stderr
    times = json.loads(stats.read_text())["time_breakdown_ms"]
    assert times["auxiliary_images"] > 0 and times["denoise"] > 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["probe.pfm", "s.json", "x.normal.pfm",
                                                         "x.pfm"]


def test_an_oidn_failure_is_one_message_and_no_output(tmp_path):
    require_oidn(tmp_path)
    (tmp_path / "x.png").write_bytes(b"old")
    result = rtcl("--size", "16x12", "--denoise", "--aov", "depth", "-o", str(tmp_path / "x.png"),
                  env={"RTCL_TEST_OIDN_FILTER": "NoSuchFilter"})
    assert result.returncode == 1
    assert result.stderr.count("\n") == 1, result.stderr
    assert "--denoise: Open Image Denoise failed" in result.stderr
    assert "NoSuchFilter" in result.stderr
    assert (tmp_path / "x.png").read_bytes() == b"old"
    assert not (tmp_path / "x.depth.pfm").exists()


def test_the_image_is_the_same_with_aov(tmp_path):
    """The auxiliary pass runs after the image, in a program whose tracer is the
    same: the image's bytes do not change."""
    scene = str(ROOT / "scenes" / "two_balls.json")
    plain, with_aov = tmp_path / "plain.pfm", tmp_path / "aov.pfm"
    for out, extra in ((plain, []), (with_aov, ["--aov", "albedo,normal,depth"])):
        result = rtcl(scene, "--size", "24x16", "--spp", "3", "-o", str(out), *extra)
        assert result.returncode == 0, result.stderr
    assert plain.read_bytes() == with_aov.read_bytes()


def test_path_traced_albedo_normal_and_denoise(tmp_path):
    """Under the path integrator the albedo is the BSDF's reflectance
    (scenes/cornell.json: the red and green walls) and the normal the
    shading normal facing the camera; --denoise brings the displayed image
    (clamped to [0, 1]: the lamp's edges dominate an HDR error) closer to a
    128-spp render."""
    scene = str(ROOT / "scenes" / "cornell.json")

    def image(name, *args):
        out = tmp_path / name
        result = rtcl(scene, "--size", "32x32", "-o", str(out), *args)
        assert result.returncode == 0, result.stderr
        return read_pfm(out)

    noisy = image("noisy.pfm", "--spp", "8", "--aov", "albedo,normal")
    albedo, normal = read_pfm(tmp_path / "noisy.albedo.pfm"), read_pfm(tmp_path / "noisy.normal.pfm")
    assert np.allclose(albedo[16, 1], [0.570068, 0.0430135, 0.0443706], atol=1e-6)  # red
    assert np.allclose(albedo[16, 30], [0.105421, 0.37798, 0.076425], atol=1e-6)  # green
    assert np.allclose(normal[16, 1], [1, 0, 0], atol=1e-6)
    assert np.allclose(normal[16, 30], [-1, 0, 0], atol=1e-6)
    assert np.allclose(normal[30, 16], [0, 1, 0], atol=1e-6)  # the floor
    require_oidn(tmp_path)
    truth = np.clip(image("truth.pfm", "--spp", "128"), 0, 1)
    denoised = np.clip(image("denoised.pfm", "--spp", "8", "--denoise"), 0, 1)

    def rmse(a):
        return float(np.sqrt(np.mean((np.clip(a, 0, 1) - truth) ** 2)))

    assert rmse(denoised) < 0.8 * rmse(noisy), (rmse(denoised), rmse(noisy))


def test_an_interrupted_render_keeps_its_auxiliary_images_of_the_samples_done(tmp_path):
    """Ctrl-C between passes (test_partial.py): the auxiliary images average
    the samples the image holds, exactly those of a render of that many."""
    from test_partial import LONG, finish, png_samples, read_terminal, share_done, start
    process, controller = start(*LONG, "-o", "out.png", "--aov", "albedo,normal,depth",
                                cwd=tmp_path)
    read_terminal(controller, share_done(5))
    process.send_signal(signal.SIGINT)
    stdout, _ = finish(process, controller)
    assert process.returncode == 128 + signal.SIGINT, stdout
    done, _ = png_samples(tmp_path / "out.png")
    assert 16 <= done < 1024, done
    whole = tmp_path / "whole"
    whole.mkdir()
    result = rtcl(*LONG[:2], "--spp", str(done), "--aov", "albedo,normal,depth", "-o",
                  str(whole / "out.png"))
    assert result.returncode == 0, result.stderr
    for kind in KINDS:
        assert ((tmp_path / f"out.{kind}.pfm").read_bytes()
                == (whole / f"out.{kind}.pfm").read_bytes()), kind
