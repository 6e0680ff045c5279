"""End-to-end tests of the rtcl command line: every option, every error message.

Each test runs the built ./rtcl (or $RTCL) on the first OpenCL device (PoCL in
CI) at tiny sizes. A failing run must print exactly one line on stderr, exit
non-zero and leave no file behind.
"""
import json
import os
import pathlib
import re
import subprocess

import pytest

import builds

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
BAD_SCENES = ROOT / "test" / "bad_scenes"
SMALL = ["--size", "24x16"]


def rtcl(*args, cwd=None):
    return subprocess.run([RTCL, *args], capture_output=True, text=True, cwd=cwd or ROOT,
                          timeout=300)


def netpbm_header(path):
    """Returns (magic, width, height) of a PPM/PFM file, skipping comments."""
    fields = []
    with open(path, "rb") as f:
        data = f.read(4096)
    for line in data.split(b"\n"):
        if line.startswith(b"#"):
            continue
        fields += line.split()
        if len(fields) >= 3:
            return fields[0].decode(), int(fields[1]), int(fields[2])
    raise AssertionError(f"{path}: no header")


def expect_failure(result, status, message, directory):
    assert result.returncode == status, (result.returncode, result.stderr)
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert message in lines[0], lines[0]
    assert result.stdout == ""
    assert sorted(os.listdir(directory)) == [], "a failed run left files behind"


# ---- what works -----------------------------------------------------------

def test_help_teaches_every_option():
    result = rtcl("--help")
    assert result.returncode == 0
    for option in ["-k, --kernel", "-w, --workgroup", "--groups", "-s, --scene", "-o, --output",
                   "--size", "--depth", "-p, --platform", "-d, --device", "--list-devices",
                   "-r, --repeat", "--stats", "-q, --quiet", "-v, --verbose", "-h, --help",
                   "--version", "serial", "naive", "cyclic", "dynamic", "persistent", "wavefront",
                   "reference", "--batch", "--queues", "--flops", "--work-map",
                   "Examples:"]:
        assert option in result.stdout, option
    assert rtcl("-h").stdout == result.stdout


def test_version():
    result = rtcl("--version")
    assert result.returncode == 0
    assert result.stdout.startswith("rtcl ")


def test_list_devices_in_clinfo_style():
    result = rtcl("--list-devices")
    assert result.returncode == 0
    assert result.stdout.startswith("Platform #0: ")
    assert "-- Device #0: " in result.stdout


@pytest.mark.parametrize("kernel", ["serial", "naive", "cyclic", "dynamic", "persistent",
                                    "wavefront", "reference"])
def test_each_kernel_renders(kernel, tmp_path):
    out = tmp_path / "img.ppm"
    result = rtcl("-k", kernel, *SMALL, "-o", str(out))
    assert result.returncode == 0, result.stderr
    assert netpbm_header(out) == ("P6", 24, 16)
    assert os.path.getsize(out) > 24 * 16 * 3
    assert f"kernel:  {kernel}" in result.stdout
    assert "device:  " in result.stdout and "time:    " in result.stdout


def test_default_is_dynamic_8x8_render_png(tmp_path):
    result = rtcl(*SMALL, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "kernel:  dynamic, work-group 8x8," in result.stdout
    with open(tmp_path / "render.png", "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"
    assert sorted(os.listdir(tmp_path)) == ["render.png"]


def stats_of(tmp_path, *args):
    out, stats = tmp_path / "img.ppm", tmp_path / "stats.json"
    result = rtcl(*args, "-o", str(out), "--stats", str(stats))
    assert result.returncode == 0, result.stderr
    with open(stats) as f:
        return result, json.load(f)


def test_stats_has_every_figure(tmp_path):
    result, stats = stats_of(tmp_path, *SMALL, "-k", "cyclic", "-w", "4x2", "--groups", "3x2",
                             "-r", "3")
    assert stats["kernel"] == "cyclic"
    assert stats["workgroup"] == "4x2"
    assert stats["groups"] == "3x2"
    assert stats["global_size"] == [12, 4]
    assert (stats["width"], stats["height"]) == (24, 16)
    assert stats["repeat"] == 3 and len(stats["kernel_ms_all"]) == 3
    assert stats["kernel_ms_min"] <= stats["kernel_ms"] <= stats["kernel_ms_max"]
    assert sorted(stats["kernel_ms_all"])[1] == stats["kernel_ms"]
    assert stats["device"] in result.stdout
    assert "median of 3 launches" in result.stdout
    # Each frame's wall time holds its launches' kernel time (the host's
    # clock around the profiled launches; 0.5 ms for the two clocks' reading).
    assert len(stats["frame_ms_all"]) == 3
    assert sorted(stats["frame_ms_all"])[1] == stats["frame_ms"]
    assert all(wall >= kernels - 0.5
               for wall, kernels in zip(stats["frame_ms_all"], stats["kernel_ms_all"]))
    assert stats["queues"] == 1  # a CPU's default


def test_stats_on_several_queues_count_overlapping_launches_once(tmp_path):
    # --queues 3: three launches a pass, which may overlap; a frame's kernel
    # time is the time any of them ran, so never more than its wall time.
    _, stats = stats_of(tmp_path, *SMALL, "-k", "dynamic", "--queues", "3", "--spp", "4",
                        "-r", "3")
    assert stats["queues"] == 3
    assert all(0 < kernels <= wall + 0.5
               for wall, kernels in zip(stats["frame_ms_all"], stats["kernel_ms_all"]))


def test_stats_has_the_devices_compute_units_and_clock(tmp_path):
    _, stats = stats_of(tmp_path, *SMALL, "-p", "0", "-d", "0")
    listing = rtcl("--list-devices").stdout
    device_line = next(line for line in listing.splitlines() if "Device #0" in line)
    units = int(re.search(r"(\d+) compute units", device_line).group(1))
    assert stats["compute_units"] == units >= 1
    assert isinstance(stats["max_clock_mhz"], int) and stats["max_clock_mhz"] >= 0
    # The CPU reference opens no OpenCL device: no device figures to report.
    _, reference = stats_of(tmp_path, *SMALL, "-k", "reference")
    assert "compute_units" not in reference and "max_clock_mhz" not in reference


def test_size_depth_and_scene_options(tmp_path):
    _, stats = stats_of(tmp_path, "-s", "scenes/two_balls.json", "--size", "30x20", "--depth",
                        "2")
    assert (stats["width"], stats["height"], stats["max_depth"]) == (30, 20, 2)
    assert stats["scene"] == "scenes/two_balls.json"
    assert netpbm_header(tmp_path / "img.ppm") == ("P6", 30, 20)


def test_scene_size_used_without_size_option(tmp_path):
    _, stats = stats_of(tmp_path, "-s", "scenes/empty.json")
    with open(ROOT / "scenes" / "empty.json") as f:
        image = json.load(f)["image"]
    assert (stats["width"], stats["height"]) == (image["width"], image["height"])


def test_platform_and_device_options(tmp_path):
    _, stats = stats_of(tmp_path, *SMALL, "-p", "0", "-d", "0")
    assert stats["device"]


def test_depth_changes_the_image(tmp_path):
    images = []
    for depth in ["0", "5"]:
        out = tmp_path / f"d{depth}.ppm"
        assert rtcl("-s", "scenes/two_balls.json", *SMALL, "--depth", depth, "-o",
                    str(out)).returncode == 0
        images.append(out.read_bytes().split(b"\n255\n", 1)[1])
    assert images[0] != images[1]


def test_quiet_prints_nothing(tmp_path):
    result = rtcl(*SMALL, "-q", "-o", str(tmp_path / "x.ppm"))
    assert result.returncode == 0
    assert result.stdout == "" and result.stderr == ""


def test_verbose_says_where_the_scene_lives(tmp_path):
    result = rtcl(*SMALL, "-v", "-o", str(tmp_path / "x.ppm"))
    assert result.returncode == 0
    assert "build options: -cl-std=CL1.2" in result.stderr
    assert "__local memory" in result.stderr


@pytest.mark.parametrize("ext,magic", [
    ("png", b"\x89PNG"), ("exr", b"\x76\x2f\x31\x01"), ("tif", b"II*\x00"),
    ("jpg", b"\xff\xd8\xff"), ("ppm", b"P6"), ("pfm", b"PF"),
])
def test_output_formats_from_extension(tmp_path, ext, magic):
    out = tmp_path / f"img.{ext}"
    result = rtcl(*SMALL, "-o", str(out))
    if result.returncode != 0 and "no OpenImageIO" in result.stderr:
        pytest.skip("built with OIIO=0")
    assert result.returncode == 0, result.stderr
    assert out.read_bytes()[:len(magic)] == magic
    assert sorted(os.listdir(tmp_path)) == [f"img.{ext}"], "temporary files left behind"


# ---- bad options ------------------------------------------------------------

@pytest.mark.parametrize("args,status,message", [
    (["-k", "bogus"], 2, '-k/--kernel: unknown kernel "bogus" (choose from serial, naive, cyclic,'
                         ' dynamic, persistent, wavefront, reference)'),
    (["--batch", "0"], 2, '--batch: expected an integer between 1 and 4096, got "0"'),
    (["--queues", "0"], 2, '--queues: expected an integer between 1 and 4, got "0"'),
    (["--queues", "5"], 2, '--queues: expected an integer between 1 and 4, got "5"'),
    (["--queues", "two"], 2, '--queues: expected an integer between 1 and 4, got "two"'),
    (["-k", "reference", "--flops", "f.npy"], 2, "the reference renderer does not count"),
    (["-w", "0x8"], 2, "-w/--workgroup: each size must be between 1 and 65536, got 0x8"),
    (["-w", "8"], 2, '-w/--workgroup: expected WxH (e.g. 8x8), got "8"'),
    (["-w", "8x8x"], 2, '-w/--workgroup: expected WxH (e.g. 8x8), got "8x8x"'),
    (["--groups", "0x0"], 2, "--groups: each size must be between 1 and 65536, got 0x0"),
    (["--size", "0x0"], 2, "--size: each size must be between 1 and 32768, got 0x0"),
    (["--size", "40000x10"], 2, "--size: each size must be between 1 and 32768, got 40000x10"),
    (["--depth", "-1"], 2, '--depth: expected an integer between 0 and 64, got "-1"'),
    (["--depth", "65"], 2, '--depth: expected an integer between 0 and 64, got "65"'),
    (["-r", "0"], 2, '-r/--repeat: expected an integer between 1 and 100000, got "0"'),
    (["-r", "two"], 2, '-r/--repeat: expected an integer between 1 and 100000, got "two"'),
    (["-p", "-1"], 2, '-p/--platform: expected an integer between 0 and 1000, got "-1"'),
    (["--accel", "octree"], 2, '--accel: expected bvh, bvh-compact or none, got "octree"'),
    (["--accel"], 2, "--accel needs a value (see --help)"),
    (["--bogus"], 2, "unknown option --bogus (see --help)"),
    (["-x"], 2, "unknown option -x (see --help)"),
    (["-k"], 2, "-k needs a value (see --help)"),
    (["a.json", "b.json"], 2,
     'two scenes given, "a.json" and "b.json": give one, as the argument or with -s/--scene'),
    (["-s", "a.json", "b.json"], 2, 'two scenes given, "a.json" and "b.json"'),
    (["--sze", "8x8"], 2, 'unknown option --sze (see --help); did you mean "--size"?'),
    (["--kernl", "naive"], 2, 'unknown option --kernl (see --help); did you mean "--kernel"?'),
    (["-t", "tpu"], 2, '-t/--type: expected gpu, cpu or all, got "tpu"'),
    (["-t"], 2, "-t needs a value (see --help)"),
    (["-q", "-v"], 2, "-q/--quiet and -v/--verbose contradict each other"),
    (["-p", "99"], 1, "platform 99 does not exist"),
    (["-d", "99"], 1, "device 99 does not exist on platform 0"),
    (["-w", "128x128"], 1, "work-group 128x128 (16384 work-items) is larger than"),
    (["--size", "32768x32768"], 1, "the image needs 12884901888 bytes of device memory"),
])
def test_bad_option(tmp_path, args, status, message):
    result = rtcl("-o", str(tmp_path / "out.png"), *args)
    expect_failure(result, status, message, tmp_path)
    assert result.stderr.startswith("rtcl: ")


def test_bogus_option_gets_no_suggestion(tmp_path):
    result = rtcl("-o", str(tmp_path / "out.png"), "--bogus")
    expect_failure(result, 2, "unknown option --bogus (see --help)", tmp_path)
    assert "did you mean" not in result.stderr


# ---- the scene as the argument, -t/--type, -v's bounds ------------------------

def test_scene_as_the_argument_is_the_scene_of_s(tmp_path):
    given = rtcl("scenes/two_balls.json", *SMALL, "-o", str(tmp_path / "a.ppm"))
    assert given.returncode == 0, given.stderr
    assert "two_balls.json" in given.stdout
    with_s = rtcl("-s", "scenes/two_balls.json", *SMALL, "-o", str(tmp_path / "b.ppm"))
    assert with_s.returncode == 0, with_s.stderr
    assert (tmp_path / "a.ppm").read_bytes() == (tmp_path / "b.ppm").read_bytes()
    # Before the options too.
    before = rtcl(*SMALL, "-o", str(tmp_path / "c.ppm"), "scenes/two_balls.json")
    assert before.returncode == 0, before.stderr
    assert (tmp_path / "c.ppm").read_bytes() == (tmp_path / "a.ppm").read_bytes()


def test_scene_argument_that_does_not_exist_is_a_scene_error(tmp_path):
    result = rtcl("no_such_scene.json", "-o", str(tmp_path / "x.png"))
    expect_failure(result, 1, "no_such_scene.json", tmp_path)


def has_gpu():
    listed = rtcl("--list-devices")
    return "(GPU" in listed.stdout


def test_type_cpu_renders_on_a_cpu(tmp_path):
    if "(CPU" not in rtcl("--list-devices").stdout:
        pytest.skip("no CPU device")
    result = rtcl("-t", "cpu", "-v", *SMALL, "-o", str(tmp_path / "x.ppm"))
    assert result.returncode == 0, result.stderr
    assert re.search(r"rtcl: platform \d+, device \d+: ", result.stderr)
    assert rtcl("-t", "all", *SMALL, "-o", str(tmp_path / "y.ppm")).returncode == 0


@pytest.mark.parametrize("args,message", [
    ([], "no GPU found; --list-devices shows what there is"),
    (["-p", "0"], "no GPU found on platform 0; --list-devices shows what there is"),
    (["-p", "0", "-d", "0"], "-t/--type gpu: device 0:0 ("),
    (["--devices", "all"], "--devices all: no GPU found; --list-devices shows what there is"),
    (["--devices", "0:0"], "--devices 0:0: -t/--type gpu: device 0:0 ("),
])
def test_type_gpu_without_a_gpu_is_one_clear_error(tmp_path, args, message):
    if has_gpu():
        pytest.skip("this machine has a GPU")
    result = rtcl("-t", "gpu", *args, *SMALL, "-o", str(tmp_path / "x.png"))
    expect_failure(result, 1, message, tmp_path)


def test_verbose_prints_the_scene_bounds(tmp_path):
    result = rtcl("-v", "-s", "scenes/two_balls.json", *SMALL, "-o", str(tmp_path / "x.ppm"))
    assert result.returncode == 0, result.stderr
    with open(ROOT / "scenes" / "two_balls.json") as f:
        scene = json.load(f)
    spheres = scene["spheres"]
    lo = [min(s["center"][a] - s["radius"] for s in spheres) for a in range(3)]
    hi = [max(s["center"][a] + s["radius"] for s in spheres) for a in range(3)]
    line = next(l for l in result.stderr.splitlines() if "scene bounds" in l)
    numbers = [float(x) for x in re.findall(r"-?[\d.]+(?:e-?\d+)?", line.split(":", 2)[2])]
    assert numbers[:6] == pytest.approx(lo + hi, rel=1e-5), line
    planes = len(scene.get("planes", []))
    assert (f"{planes} plane" in line and "infinite" in line) == (planes > 0), line
    empty = rtcl("-v", "-s", "scenes/empty.json", *SMALL, "-o", str(tmp_path / "y.ppm"))
    assert "rtcl: scene bounds: no sphere or triangle" in empty.stderr


def test_flop_count_buffer_too_large(tmp_path):
    """An image that just fits the device's largest buffer, whose flop count
    buffer (8 bytes per work-item, twice, and per pixel) does not."""
    probe = rtcl("-o", str(tmp_path / "out.png"), "--size", "32768x32768")
    limit = int(re.search(r"allows at most (\d+) bytes", probe.stderr).group(1))
    height = limit // 12 // 32768
    if not 1 <= height <= 32768:
        pytest.skip(f"the device allows {limit} bytes in one buffer")
    result = rtcl("-k", "naive", "-o", str(tmp_path / "out.png"), "--size", f"32768x{height}",
                  "--flops", str(tmp_path / "flops.npy"))
    expect_failure(result, 1, "the flop count buffer needs ", tmp_path)


def test_sample_sums_buffer_too_large(tmp_path):
    """An image that fits the device's largest buffer whose samples' sums (32
    bytes a pixel against the image's 12) do not: refused before rendering."""
    probe = rtcl("-o", str(tmp_path / "out.png"), "--size", "32768x32768")
    limit = int(re.search(r"allows at most (\d+) bytes", probe.stderr).group(1))
    height = limit // 12 // 32768
    if not 1 <= height <= 32768 or 32 * 32768 * height <= limit:
        pytest.skip(f"the device allows {limit} bytes in one buffer")
    result = rtcl("-o", str(tmp_path / "out.png"), "--size", f"32768x{height}", "--spp", "2")
    expect_failure(result, 1, "the sample sums buffer (32 bytes a pixel) needs ", tmp_path)


def test_unwritable_output_directory(tmp_path):
    result = rtcl(*SMALL, "-o", str(tmp_path / "missing" / "out.png"))
    expect_failure(result, 1, "does not exist", tmp_path)


def test_output_in_unwritable_place(tmp_path):
    result = rtcl(*SMALL, "-o", "/proc/rtcl-test.png")
    assert result.returncode == 1
    assert len(result.stderr.splitlines()) == 1
    assert not os.path.exists("/proc/rtcl-test.png")


@pytest.mark.parametrize("name,message", [
    ("out.xyz", 'unknown image format ".xyz"'),
    ("out", "no file extension"),
])
def test_unknown_output_format(tmp_path, name, message):
    result = rtcl(*SMALL, "-o", str(tmp_path / name))
    expect_failure(result, 1, message, tmp_path)


def test_output_that_is_a_directory(tmp_path):
    (tmp_path / "d.png").mkdir()
    result = rtcl(*SMALL, "-o", str(tmp_path / "d.png"))
    assert result.returncode == 1
    assert "not a regular file" in result.stderr
    assert os.listdir(tmp_path / "d.png") == []


def test_stats_in_missing_directory_writes_no_image(tmp_path):
    out = tmp_path / "out.png"
    result = rtcl(*SMALL, "-o", str(out), "--stats", str(tmp_path / "missing" / "s.json"))
    expect_failure(result, 1, "does not exist", tmp_path)


# ---- bad scenes ---------------------------------------------------------------

BAD = sorted(p.stem for p in BAD_SCENES.glob("*.json"))


@pytest.mark.parametrize("name", BAD)
def test_bad_scene_message(tmp_path, name):
    scene = BAD_SCENES / f"{name}.json"
    want = (BAD_SCENES / f"{name}.expect").read_text().rstrip("\n")
    out = tmp_path / "out.png"
    result = rtcl("-s", str(scene), "-o", str(out))
    assert result.returncode == 1
    assert result.stderr == want.replace("{FILE}", str(scene)) + "\n"
    assert result.stdout == ""
    assert os.listdir(tmp_path) == []


def test_scene_with_byte_order_mark_renders(tmp_path):
    """SCENE.md: a UTF-8 byte-order mark at the start of the file is skipped."""
    scene = tmp_path / "bom.json"
    scene.write_bytes(b"\xef\xbb\xbf" + (ROOT / "scenes" / "two_balls.json").read_bytes())
    result = rtcl("-s", str(scene), "-o", str(tmp_path / "out.ppm"), *SMALL)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "out.ppm").stat().st_size > 0


def test_bad_scene_leaves_existing_output_untouched(tmp_path):
    out = tmp_path / "out.png"
    out.write_bytes(b"precious")
    result = rtcl("-s", str(BAD_SCENES / "sphere_negative_radius.json"), "-o", str(out))
    assert result.returncode == 1
    assert out.read_bytes() == b"precious"


def test_missing_scene_file(tmp_path):
    missing = tmp_path / "missing.json"
    result = rtcl("-s", str(missing), "-o", str(tmp_path / "out.png"))
    expect_failure(result, 1, f"{missing}: cannot open: No such file or directory", tmp_path)


def test_directory_as_scene(tmp_path):
    scene_dir = tmp_path / "scene.json"
    scene_dir.mkdir()
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    result = rtcl("-s", str(scene_dir), "-o", str(out_dir / "out.png"))
    expect_failure(result, 1, f"{scene_dir}: not a regular file", out_dir)


# ---- counting ------------------------------------------------------------------

def test_flops_file_and_figures(tmp_path):
    np = pytest.importorskip("numpy")
    flops = tmp_path / "f.npy"
    result, stats = stats_of(tmp_path, *SMALL, "-k", "cyclic", "-w", "4x4", "--groups", "2x3",
                             "--flops", str(flops), "--work-map", str(tmp_path / "map.ppm"))
    counts = np.load(flops)
    assert counts.dtype == np.dtype("<u8")
    assert counts.shape == (12, 8)  # global size: 3 groups of 4 high, 2 of 4 wide
    with open(str(flops) + ".json") as f:
        sidecar = json.load(f)
    assert sidecar["format"] == "rtcl-flops"
    assert sidecar["global_size"] == [8, 12] and sidecar["groups"] == [2, 3]
    assert sidecar["total_flops"] == int(counts.sum()) > 0
    efficiency = counts.mean() / counts.max()
    assert sidecar["parallel_efficiency"] == pytest.approx(efficiency)
    assert stats["parallel_efficiency"] == pytest.approx(efficiency)
    assert stats["gflop"] == pytest.approx(counts.sum() * 1e-9)
    assert stats["flops_per_item"]["max"] == counts.max()
    assert stats["gflops"] == pytest.approx(counts.sum() * 1e-6 / stats["kernel_ms"])
    assert stats["rays"] >= 24 * 16
    assert "parallel efficiency" in result.stdout
    magic, width, height = netpbm_header(tmp_path / "map.ppm")
    assert (magic, width, height) == ("P6", 24, 16)  # the render's size; the bar: --work-map-bar


@pytest.mark.slow  # Criterion's flops::kernels_count_the_same_work checks the same per kernel
def test_same_flops_whatever_the_kernel(tmp_path):
    totals = set()
    for kernel in ["serial", "naive", "dynamic", "persistent", "wavefront"]:
        _, stats = stats_of(tmp_path, *SMALL, "-k", kernel, "--flops", str(tmp_path / "f.npy"))
        totals.add(stats["total_flops"])
    assert len(totals) == 1


def test_flops_in_missing_directory_writes_nothing(tmp_path):
    result = rtcl(*SMALL, "-o", str(tmp_path / "out.png"), "--flops",
                  str(tmp_path / "missing" / "f.npy"))
    expect_failure(result, 1, "does not exist", tmp_path)


@pytest.mark.parametrize("signal_name", ["SIGINT", "SIGTERM"])
def test_interrupted_render_leaves_no_file(tmp_path, signal_name):
    import signal
    import time
    out = tmp_path / "out.png"
    # The serial kernel on a CPU takes seconds at this size, long enough to
    # interrupt, even with PoCL's optimised build (1500x1500 took 0.8 s).
    process = subprocess.Popen([RTCL, "-k", "serial", "--size", "4000x4000", "-o", str(out),
                                "--stats", str(tmp_path / "s.json")],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(1.0)
    process.send_signal(getattr(signal, signal_name))
    stdout, stderr = process.communicate(timeout=60)
    assert process.returncode == 128 + getattr(signal, signal_name)
    assert stderr == "rtcl: interrupted; no output written\n"
    assert stdout == ""
    assert os.listdir(tmp_path) == []


# ---- limits ----------------------------------------------------------------------

def test_accel_bvh_is_the_default_and_matches_none(tmp_path):
    """--accel bvh (the default), bvh-compact and none give the same image; --stats
    says which, with the BVH's size, and with --flops the node visits (none for
    brute force)."""
    images = {}
    for accel in ("bvh", "bvh-compact", "none", None):
        name = accel or "default"
        args = ["--accel", accel] if accel else []
        (tmp_path / name).mkdir()
        result, stats = stats_of(tmp_path / name, *SMALL, *args, "-v",
                                 "--flops", str(tmp_path / f"{name}.npy"))
        images[name] = (tmp_path / name / "img.ppm").read_bytes()
        assert stats["accel"] == (accel or "bvh")
        if stats["accel"] != "none":   # bvh-compact builds spheres as bvh does
            assert stats["bvh"]["nodes"] == 16 and stats["bvh"]["depth"] >= 4
            assert stats["node_visits"] > 0 and stats["node_visits_per_ray"] > 1
            # Each leaf visited tests at least one sphere.
            assert 0 < stats["leaf_visits"] <= stats["primitive_tests"]
            assert stats["primitive_tests_per_ray"] == pytest.approx(
                stats["primitive_tests"] / stats["rays"])
            assert "rtcl: BVH of 60 spheres and 0 triangles: 16 nodes" in result.stderr
            assert "-DRTCL_BVH" in stats["build_options"]
            assert "BVH node visits" in result.stdout
        else:
            assert "bvh" not in stats and stats["node_visits"] == 0
            assert stats["leaf_visits"] == stats["primitive_tests"] == 0
            assert "-DRTCL_BVH" not in stats["build_options"]
            assert "BVH" not in result.stderr + result.stdout
    assert images["bvh"] == images["none"] == images["default"] == images["bvh-compact"]


@pytest.mark.parametrize("scene, triangles", [("paper60.json", False),
                                              ("glass_mesh.json", True)])
def test_triangle_code_is_built_only_for_scenes_with_triangles(tmp_path, scene, triangles):
    """A scene without triangles is built with -DRTCL_NO_TRIANGLES (fewer
    registers); one with triangles without it."""
    _, stats = stats_of(tmp_path, *SMALL, "-s", str(ROOT / "scenes" / scene))
    assert ("-DRTCL_NO_TRIANGLES" not in stats["build_options"]) == triangles


@pytest.mark.parametrize("spp, one_sample", [("1", True), ("2", False)])
def test_one_sample_code_is_built_only_for_one_sample_per_pixel(tmp_path, spp, one_sample):
    """--spp 1 is built with -DRTCL_ONE_SAMPLE (no sample loop: fewer
    registers); more samples without it."""
    _, stats = stats_of(tmp_path, *SMALL, "--spp", spp)
    assert ("-DRTCL_ONE_SAMPLE" in stats["build_options"]) == one_sample


@pytest.mark.slow
def test_million_spheres_render_from_global_memory(tmp_path):
    """A scene far larger than __local memory is read from __global memory."""
    scene = tmp_path / "million.json"
    with open(scene, "w") as f:
        f.write('{"format": "rtcl-scene", "version": 1, "image": {"width": 4, "height": 3},'
                ' "camera": {"eye": [0, 0, -5], "look_at": [0, 0, 0]},'
                ' "lights": [{"position": [0, 5, -5]}], "spheres": [')
        f.write(",".join('{"center": [%d, %d, %d], "radius": 0.01}'
                         % (i % 100 - 50, i // 100 % 100 - 50, i // 10000 + 5)
                         for i in range(1000000)))
        f.write("]}")
    out = tmp_path / "out.ppm"
    result = rtcl("-s", str(scene), "-o", str(out), "-v", "-k", "dynamic", "-w", "4x3")
    assert result.returncode == 0, result.stderr
    assert ("read from __global memory (it would take more than a third of __local memory)"
            in result.stderr)
    assert netpbm_header(out) == ("P6", 4, 3)


@pytest.mark.parametrize("extra", [[], ["--devices", "0:0", "--piece-rows", "2000"],
                                   ["-k", "wavefront"]], ids=["one", "devices", "wavefront"])
@pytest.mark.skipif(builds.built_with_asan(RTCL),
                    reason="AddressSanitizer cannot run under an address-space limit")
def test_too_little_host_memory_is_one_message(tmp_path, extra):
    """Issue 24 finding 6: under `ulimit -v 1500000` an 8000x8000 image on PoCL
    aborted in PoCL's assertion (rc 134), as PoCL allocated the image buffer at
    the first launch; buffers of a device that shares the host's memory are now
    allocated when created, on every path."""
    import resource
    if "(CPU" not in rtcl("--list-devices").stdout.splitlines()[1]:
        pytest.skip("the first device is not a CPU device")

    def limit_address_space():
        resource.setrlimit(resource.RLIMIT_AS, (1_500_000 * 1024, 1_500_000 * 1024))
    # The program first, without the limit: with cold caches PoCL's compiler
    # (LLVM) may itself run out under it and crash, which rtcl cannot catch.
    warm = rtcl("--size", "8x8", *extra, "-o", str(tmp_path / "warm.png"))
    assert warm.returncode == 0, warm.stderr
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    result = subprocess.run([RTCL, "--size", "8000x8000", *extra, "-o", str(out_dir / "x.png")],
                            capture_output=True, text=True, timeout=300,
                            preexec_fn=limit_address_space)
    expect_failure(result, 1, "out of host memory for the image (768000000 bytes)", out_dir)


def test_kernel_build_failure_shows_log_and_options(tmp_path):
    cl_dir = tmp_path / "cl"
    cl_dir.mkdir()
    for source in (ROOT / "cl").iterdir():
        (cl_dir / source.name).write_text(source.read_text())
    with open(cl_dir / "tracer.cl", "a") as f:
        f.write("\nthis is not OpenCL C;\n")
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    result = subprocess.run([RTCL, *SMALL, "-o", str(out_dir / "x.png")], capture_output=True,
                            text=True, env={**os.environ, "RTCL_CL_DIR": str(cl_dir)},
                            timeout=300)
    assert result.returncode == 1
    # PoCL's compiler prints its own "N errors generated." before rtcl's message.
    assert "rtcl: building kernel 'dynamic' for " in result.stderr
    assert "failed: CL_BUILD_PROGRAM_FAILURE" in result.stderr
    assert "options: -cl-std=CL1.2 -DRTCL_MAX_DEPTH=5" in result.stderr
    assert "build log:" in result.stderr and "error" in result.stderr
    assert os.listdir(out_dir) == []


def test_missing_kernel_source_directory(tmp_path):
    result = subprocess.run([RTCL, *SMALL, "-o", str(tmp_path / "x.png")], capture_output=True,
                            text=True, env={**os.environ, "RTCL_CL_DIR": str(tmp_path / "nope")},
                            timeout=300)
    assert result.returncode == 1
    assert f"rtcl: {tmp_path / 'nope' / 'rtcl_shared.h'}: cannot open: No such file or directory" \
        in result.stderr
    assert os.listdir(tmp_path) == []


def test_wavefront_flops_file_holds_every_launch(tmp_path):
    np = pytest.importorskip("numpy")
    flops = tmp_path / "w.npy"
    _, stats = stats_of(tmp_path, *SMALL, "-k", "wavefront", "--flops", str(flops))
    counts = np.load(flops)
    assert counts.shape[0] == 1 and counts.shape[1] > 24 * 16  # primary launch + bounces
    assert int(counts.sum()) == stats["total_flops"]
    assert stats["parallel_efficiency"] == pytest.approx(counts.mean() / counts.max())


@pytest.mark.parametrize("option", ["-o", "--stats", "--flops", "--work-map"])
def test_output_to_a_device_file_is_refused(tmp_path, option):
    out_dir, target = tmp_path / "out", "/dev/full"
    out_dir.mkdir()
    if option == "--flops":  # it takes only a .npy name: reach /dev/full through a link
        target = str(tmp_path / "full.npy")
        os.symlink("/dev/full", target)
    args = ["-o", str(out_dir / "x.ppm")] if option != "-o" else []
    result = rtcl(*SMALL, *args, option, target)
    assert result.returncode == 1
    assert len(result.stderr.splitlines()) == 1 and target in result.stderr
    assert os.listdir(out_dir) == []


def test_very_long_name_gives_a_short_message(tmp_path):
    scene = tmp_path / "long.json"
    scene.write_text(json.dumps({
        "format": "rtcl-scene", "version": 1,
        "camera": {"eye": [0, 0, -5], "look_at": [0, 0, 0]},
        "spheres": [{"center": [0, 0, 0], "radius": 1, "material": "m" * 100000}]}))
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    result = rtcl("-s", str(scene), "-o", str(out_dir / "x.png"))
    expect_failure(result, 1, "spheres[0].material: unknown material", out_dir)
    assert len(result.stderr) < 400


def test_device_failing_mid_render_writes_nothing(tmp_path):
    """A device that fails during the render (simulated: RTCL_TEST_DEVICE_FAULT=1
    fails the last launch with CL_OUT_OF_RESOURCES) is reported by name, and no
    image or other output is written."""
    result = subprocess.run([RTCL, *SMALL, "-r", "3", "-o", str(tmp_path / "x.png"),
                             "--stats", str(tmp_path / "s.json")],
                            capture_output=True, text=True, timeout=300,
                            env={**os.environ, "RTCL_TEST_DEVICE_FAULT": "1"})
    expect_failure(result, 1, "waiting for the kernel failed (kernel 'dynamic' on ", tmp_path)
    assert result.stderr.rstrip().endswith("CL_OUT_OF_RESOURCES")


def test_depth_64_renders(tmp_path):
    """SCENE.md's largest max_depth: the ray stack is sized from it at build time."""
    _, stats = stats_of(tmp_path, "-s", "test/scenes/mirror_corridor.json", "--flops",
                        str(tmp_path / "f.npy"))
    assert stats["max_depth"] == 64
    assert "-DRTCL_MAX_DEPTH=64" in stats["build_options"]
    assert stats["rays"] > 24 * 16 * 60  # most paths bounce to the last level


def run_with_env(env, *args):
    return subprocess.run([RTCL, *args], capture_output=True, text=True,
                          env={**os.environ, **env}, timeout=300)


def test_build_options_variable_is_added_and_reported(tmp_path):
    out, stats = tmp_path / "x.ppm", tmp_path / "s.json"
    plain = tmp_path / "plain.ppm"
    assert rtcl(*SMALL, "-o", str(plain)).returncode == 0
    result = run_with_env({"RTCL_BUILD_OPTIONS": "-DRTCL_UNUSED_MARKER=7"}, *SMALL, "-v",
                          "-o", str(out), "--stats", str(stats))
    assert result.returncode == 0, result.stderr
    options = json.loads(stats.read_text())["build_options"]
    assert options.startswith("-cl-std=CL1.2 ") and options.endswith(" -DRTCL_UNUSED_MARKER=7")
    assert "rtcl: build options: " + options in result.stderr
    # A define the sources do not use leaves the image alone.
    assert out.read_bytes().split(b"\n", 3)[3] == plain.read_bytes().split(b"\n", 3)[3]


LONGEST_BUILD_OPTIONS = "-DX" + "Y" * 253  # 256 characters


@pytest.mark.slow
def test_longest_build_options_variable_is_taken_with_every_other_option(tmp_path):
    # Two programs that no other test builds (8 s with cold caches).
    out = tmp_path / "x.ppm"
    result = run_with_env({"RTCL_BUILD_OPTIONS": LONGEST_BUILD_OPTIONS}, *SMALL, "-o", str(out),
                          "--flops", str(tmp_path / "f.npy"))
    assert result.returncode == 0, result.stderr
    assert out.exists()


def test_build_options_variable_too_long_is_refused(tmp_path):
    out = tmp_path / "x.ppm"
    result = run_with_env({"RTCL_BUILD_OPTIONS": LONGEST_BUILD_OPTIONS + "Z"}, *SMALL, "-o",
                          str(out))
    assert result.returncode == 1
    assert result.stderr.strip().splitlines() == [
        "rtcl: RTCL_BUILD_OPTIONS is too long (at most 256 characters)"]
    assert not out.exists()


def test_dump_binary_writes_the_program(tmp_path):
    binary, out = tmp_path / "program.bin", tmp_path / "x.ppm"
    result = run_with_env({"RTCL_DUMP_BINARY": str(binary)}, *SMALL, "-o", str(out))
    assert result.returncode == 0, result.stderr
    assert binary.stat().st_size > 1000
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_dump_binary_into_a_missing_folder_fails_before_any_output(tmp_path):
    out = tmp_path / "x.ppm"
    result = run_with_env({"RTCL_DUMP_BINARY": str(tmp_path / "nope" / "p.bin")}, *SMALL,
                          "-o", str(out))
    assert result.returncode == 1
    assert len(result.stderr.strip().splitlines()) == 1
    assert "nope/p.bin" in result.stderr
    assert not out.exists()


def test_the_summary_gives_the_kernel_time_and_the_time_in_all(tmp_path):
    """Issue 44: the summary's time was the kernels' only, a first render's
    program build left out; it says the time in all, and the build when it
    was not cached."""
    import re
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / "cache")}
    first, second = (subprocess.run([RTCL, *SMALL, "-o", str(tmp_path / "x.ppm")],
                                    capture_output=True, text=True, timeout=300, env=env)
                     for _ in range(2))
    pattern = r"time:    ([\d.]+) ms in the kernels; ([\d.]+) s in all(, ([\d.]+) s of it " \
              r"the program build \(not cached\))?\n"
    built, cached = re.search(pattern, first.stdout), re.search(pattern, second.stdout)
    assert built and built[4] is not None, first.stdout
    assert cached and cached[4] is None, second.stdout
    for m in (built, cached):
        assert float(m[2]) * 1e3 >= float(m[1])
    assert float(built[2]) >= float(built[4])
