"""Several devices in one process (--devices, --split) and animations
(--frames), end to end under PoCL, which exposes two CPU devices with
POCL_DEVICES="pthread pthread". A slower device is simulated with
RTCL_TEST_SLOW_DEVICE=K:MS, a failing one with RTCL_TEST_FAIL_DEVICE=K:N
(host/render/checks.h)."""
import json
import os
import pathlib
import re
import signal
import struct
import subprocess
import sys
import time

import pytest

import builds

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools.ppm import pixels  # noqa: E402

TWO = {"POCL_DEVICES": "pthread pthread"}
SMALL = ["--size", "32x24"]


def run(*args, env=None):
    return subprocess.run([RTCL, *args], capture_output=True, text=True, cwd=ROOT, timeout=300,
                          env={**os.environ, **TWO, **(env or {})})


def expect_failure(result, status, message, directory):
    assert result.returncode == status, (result.returncode, result.stderr)
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert message in lines[0], lines[0]
    assert result.stdout == ""
    assert sorted(os.listdir(directory)) == [], "a failed run left files behind"


def frames_run(directory, *args, env=None):
    stats = directory / "s.json"
    result = run(*SMALL, "-o", str(directory / "f.ppm"), "--stats", str(stats), *args, env=env)
    assert result.returncode == 0, result.stderr
    return result, json.loads(stats.read_text())


def test_frames_on_two_devices_match_one_device_byte_for_byte(tmp_path):
    one, two = tmp_path / "one", tmp_path / "two"
    one.mkdir()
    two.mkdir()
    _, stats1 = frames_run(one, "--frames", "3:6", "-p", "0", "-d", "0")
    _, stats2 = frames_run(two, "--frames", "3:6", "--devices", "0:0,0:1")
    names = [f"f_{f:04d}.ppm" for f in range(3, 7)]
    assert sorted(p.name for p in two.iterdir()) == sorted(names + ["s.json"])
    for name in names:
        assert (one / name).read_bytes() == (two / name).read_bytes(), name
    # Every frame differs: the camera moves.
    assert len({pixels(two / name) for name in names}) == 4
    assert len(stats1["multidevice"]["devices"]) == 1
    assert len(stats2["multidevice"]["devices"]) == 2


def test_first_frame_is_the_scenes_camera(tmp_path):
    frames_run(tmp_path, "--frames", "0:2", "--devices", "0:1,0:0")
    plain = run(*SMALL, "-o", str(tmp_path / "plain.ppm"), "-q")
    assert plain.returncode == 0, plain.stderr
    # The same pixels (the header's description names the frame).
    assert pixels(tmp_path / "f_0000.ppm") == pixels(tmp_path / "plain.ppm")


def test_every_frame_rendered_once_and_accounted(tmp_path):
    result, stats = frames_run(tmp_path, "--frames", "1:7", "--devices", "all")
    md = stats["multidevice"]
    assert [d["index"] for d in md["devices"]] == [0, 1]
    assert sum(d["pieces"] for d in md["devices"]) == 7
    assert sum(d["pixels"] for d in md["devices"]) == 7 * 32 * 24
    busy = [d["busy_ms"] for d in md["devices"]]
    assert md["device_efficiency"] == pytest.approx(sum(busy) / 2 / max(busy), rel=1e-6)
    assert "device-level efficiency" in result.stdout
    assert "f_0001.ppm .. " in result.stdout and "f_0007.ppm" in result.stdout


@pytest.mark.parametrize("frames, pieces", [("0:2", [2, 2]), ("0:5", [2, 2, 2, 2]),
                                            ("0:0", [1, 0])])
def test_gpus_share_the_last_frames_when_fewer_remain_than_gpus(tmp_path, frames, pieces):
    # With GPUs alone (RTCL_TEST_AS_GPUS: PoCL's devices count as GPUs), the
    # last n mod G frames are each rendered over a group of the GPUs when the
    # frames so far say it pays (run/frames.c: these tiny frames take far
    # longer than a group's set-up), so none idles: 3 frames on 2 devices are
    # one each, then the third over both; 6 frames on 4 devices, one each,
    # then two groups of 2 at once (multidev_run's workers were static: the
    # groups' jobs mixed their devices). One frame on 2 devices is not shared:
    # no frame came before to say what a frame costs. Every frame is one
    # device's, byte for byte.
    one, two = tmp_path / "one", tmp_path / "two"
    one.mkdir()
    two.mkdir()
    common = ["--frames", frames, "--spp", "4"]
    frames_run(one, *common, "-d", "0")
    devices = ",".join(f"0:{k}" for k in range(len(pieces)))
    result, stats = frames_run(two, *common, "--devices", devices,
                               env={**FOUR, "RTCL_TEST_AS_GPUS": "1"})
    names = sorted(p.name for p in one.iterdir() if p.suffix == ".ppm")
    assert len(names) == int(frames[2:]) + 1
    for name in names:
        assert (one / name).read_bytes() == (two / name).read_bytes(), name
    md = stats["multidevice"]
    # A shared frame is a piece of each device of its group, which writes a
    # share of its pixels, a range of their samples on the renderer kept
    # open from its whole frames (before, each group opened renderers of its
    # own: 260-300 ms a GPU on H100s).
    assert sorted(d["pieces"] for d in md["devices"]) == sorted(pieces)
    assert [d.get("renderers_opened") for d in md["devices"] if d["pieces"]] == [1] * sum(
        1 for p in pieces if p), md["devices"]
    done = [d["pixels"] for d in md["devices"]]
    assert sum(done) == len(names) * 32 * 24
    assert all(p > (pieces[0] - 1) * 32 * 24 for p in done) or sorted(done) == [0, 32 * 24], done


@pytest.mark.parametrize("way", [None, "aside", "pageable", "inline"])
def test_frames_read_back_any_way_are_one_devices_frames(tmp_path, way):
    # RTCL_FRAMES_READ (run/frames.c): "aside" copies a frame's image on its
    # device and has the device's stager thread read it back, into one pinned
    # image a device, beside the device's next frame; "pageable", the default
    # (batch 106), the same into memory of malloc; "inline" reads it in the
    # device's thread into one of two pinned images a device, as before (on
    # four H100s 155-182 ms a device beyond the kernels, in the first frames:
    # docs/results/h100x4, batch 100). Four devices taken as GPUs, 10 frames:
    # 8 dealt whole, the last 2 shared over two groups. Every frame one
    # device's, byte for byte, a renderer opened once a device, the way,
    # each device's first frame and its renderer's opening in it reported.
    one, four = tmp_path / "one", tmp_path / "four"
    one.mkdir()
    four.mkdir()
    common = ["--frames", "0:9", "--spp", "4"]
    frames_run(one, *common, "-d", "0")
    env = {**FOUR, "RTCL_TEST_AS_GPUS": "1"}
    if way:
        env["RTCL_FRAMES_READ"] = way
    _, stats = frames_run(four, *common, "--devices", "0:0,0:1,0:2,0:3", env=env)
    names = sorted(p.name for p in one.iterdir() if p.suffix == ".ppm")
    assert len(names) == 10
    assert sorted(p.name for p in four.iterdir() if p.suffix == ".ppm") == names
    for name in names:
        assert (one / name).read_bytes() == (four / name).read_bytes(), name
    md = stats["multidevice"]
    assert md["frames_read"] == (way or "pageable")
    devices = md["devices"]
    assert sum(d["pixels"] for d in devices) == 10 * 32 * 24
    assert all(d["renderers_opened"] == 1 for d in devices if d["pieces"]), devices
    for d in devices:
        if d["pieces"]:
            assert 0 < d["open_ms"] < d["first_piece_ms"] <= d["busy_ms"], d


def test_an_unknown_way_to_read_frames_back_is_refused(tmp_path):
    result = run(*SMALL, "--frames", "0:3", "--devices", "0:0,0:1", "-o",
                 str(tmp_path / "f.ppm"), env={"RTCL_FRAMES_READ": "pinned"})
    expect_failure(result, 2, "RTCL_FRAMES_READ=pinned: expected aside, pageable or inline",
                   tmp_path)


def test_dynamic_split_gives_a_slow_device_fewer_pieces(tmp_path):
    _, stats = frames_run(tmp_path, "--frames", "0:9", "--devices", "0:0,0:1",
                          env={"RTCL_TEST_SLOW_DEVICE": "1:400"})
    pieces = [d["pieces"] for d in stats["multidevice"]["devices"]]
    assert sum(pieces) == 10
    assert pieces[1] < pieces[0], pieces
    assert stats["multidevice"]["split"] == "dynamic"


def test_static_split_gives_equal_shares_whatever_the_speed(tmp_path):
    _, stats = frames_run(tmp_path, "--frames", "0:9", "--devices", "0:0,0:1", "--split",
                          "static", env={"RTCL_TEST_SLOW_DEVICE": "1:100"})
    pieces = [d["pieces"] for d in stats["multidevice"]["devices"]]
    assert pieces == [5, 5]
    assert stats["multidevice"]["split"] == "static"


def test_a_device_failing_mid_render_writes_nothing(tmp_path):
    result = run(*SMALL, "--frames", "0:5", "--devices", "0:0,0:1", "-o",
                 str(tmp_path / "f.png"), "--stats", str(tmp_path / "s.json"),
                 # device 0 slowed, so that device 1 surely takes a second frame
                 # (under the sanitizers' build device 0 once took five of six)
                 env={"RTCL_TEST_FAIL_DEVICE": "1:2", "RTCL_TEST_SLOW_DEVICE": "0:300"})
    expect_failure(result, 1, "device 0:1 (", tmp_path)
    assert "failed on its piece 2" in result.stderr


@pytest.mark.parametrize("args, message", [
    (["--devices", "0"], "--devices: expected all or a list of PLATFORM:DEVICE indices"),
    (["--devices", "0:0,"], "--devices: expected all or a list"),
    (["--devices", "0:-1"], "--devices: expected all or a list"),
    (["--devices", "0:0,0:0"], "--devices: device 0:0 is listed twice"),
    (["--devices", "0:0", "-d", "0"], "--devices and -p/-d both choose devices"),
    (["--devices", "0:0", "-k", "reference"], "the reference renderer runs on the host"),
    (["--split", "half"], "--split: expected dynamic, static or samples, got \"half\""),
    (["--frames", "5"], "--frames: expected A:B"),
    (["--frames", "5:x"], "--frames: expected A:B"),
    (["--frames", "5:4"], "the last frame must not come before the first"),
    (["--frames", "0:1000"], "at most 1000 frames"),
    (["--frames", "0:1", "-r", "2"], "--frames renders each frame once"),
    (["--frames", "0:1", "--flops", "x.npy"], "--frames renders each frame once"),
    (["--devices", "0:0,0:1", "--piece-rows", "0"], "--piece-rows: expected"),
    (["--devices", "0:0,0:1", "--piece-rows", "2x"], "--piece-rows: expected"),
    (["--piece-rows", "4"], "--piece-rows cuts one image into bands for the devices of"),
    # Like --piece-rows: refused, not silently ignored, without several devices.
    (["--split", "static"], "--split chooses how pieces go to the devices of --devices or --mpi"),
    (["--row-order", "scan"], "--row-order orders the rows that pieces of one image take on"),
    (["--devices", "0:0,0:1", "--frames", "0:1", "--row-order", "interleave"],
     "--row-order orders the rows that pieces of one image take on the devices of --devices or "
     "--mpi; it does not apply to --frames"),
    (["--devices", "0:0,0:1", "--row-order", "zigzag"],
     "--row-order: expected interleave, interleave:S (S classes, 1..4096) or scan, got "
     "\"zigzag\""),
    (["--devices", "0:0,0:1", "--row-order", "interleave:0"], "--row-order: expected"),
    (["--devices", "0:0,0:1", "--row-order", "interleave:"], "--row-order: expected"),
    (["--split", "dynamic", "--frames", "0:1"], "--split chooses how pieces go"),
    (["--devices", "all", "--frames", "0:1", "--piece-rows", "4"],
     "it does not apply to --frames"),
    (["--devices", "0:0,0:1", "--flops", "x.npy"], "use --work-map FILE.npy (per pixel)"),
    (["--mpi", "--flops", "x.npy"], "use --work-map FILE.npy (per pixel)"),
    (["--mpi", "-r", "2"], "--mpi renders the image once"),
    (["--mpi", "--work-map", "w.png"], "--mpi renders the image once"),
    (["--devices", "0:0,0:1", "--split", "samples", "--piece-rows", "4"],
     "--split samples renders the whole image on every device, each a share of every pixel's "
     "samples; it does not go with --piece-rows (use --split dynamic or static)"),
    (["--devices", "0:0,0:1", "--split", "samples", "--work-map", "w.npy"],
     "it does not go with --work-map"),
    (["--mpi", "--split", "samples", "--frames", "0:1"], "it does not go with --frames"),
    (["--devices", "0:0,0:1", "--split", "samples", "--row-order", "scan"],
     "it does not go with --row-order"),
])
def test_option_errors(tmp_path, args, message):
    result = run(*args, "-o", str(tmp_path / "x.png"))
    expect_failure(result, 2, message, tmp_path)


def test_device_out_of_range_names_what_exists(tmp_path):
    result = run("--devices", "0:0,0:5", "-o", str(tmp_path / "x.png"))
    expect_failure(result, 1, "--devices 0:5: device 5 does not exist on platform 0: it has 2",
                   tmp_path)
    result = run("--devices", "7:0", "-o", str(tmp_path / "x.png"))
    expect_failure(result, 1, "--devices 7:0: platform 7 does not exist", tmp_path)


def test_frames_refuse_an_unwritable_frame_before_rendering(tmp_path):
    (tmp_path / "f_0002.png").mkdir()
    result = run(*SMALL, "--frames", "1:3", "-o", str(tmp_path / "f.png"))
    assert result.returncode == 1, result.stderr
    assert "f_0002.png" in result.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f_0002.png"]


def test_stats_naming_a_frame_is_refused(tmp_path):
    result = run(*SMALL, "--frames", "1:3", "-o", str(tmp_path / "f.png"), "--stats",
                 str(tmp_path / "f_0003.png"))
    # A usage error, as two outputs of one image naming one file are.
    expect_failure(result, 2, "name the same file", tmp_path)


# ---- MPI: mpirun --oversubscribe -np 3 over loopback ------------------------

MPIRUN = ["mpirun", "--oversubscribe", "-np", "3"]
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "POCL_DEVICES": "pthread", "OMPI_MCA_btl": "self,vader,tcp",
           "OMPI_MCA_orte_tmpdir_base": builds.ompi_session_base()}
# Under make test SAN=1, LeakSanitizer reports what Open MPI's components keep
# until exit from code it has unloaded at MPI_Finalize ("<unknown module>"), so
# no suppression can name it: under mpirun, ASan checks memory errors and not
# leaks (the same renders without --mpi are leak-checked).
if "ASAN_OPTIONS" in os.environ:
    MPI_ENV["ASAN_OPTIONS"] = os.environ["ASAN_OPTIONS"] + ":detect_leaks=0"


def built_with_mpi():
    probe = subprocess.run([RTCL, "--mpi", "--size", "8x8", "-o", "/nonexistent/x.png"],
                           capture_output=True, text=True, timeout=60)
    return "built without MPI" not in probe.stderr


needs_mpi = pytest.mark.skipif(
    subprocess.run(["sh", "-c", "command -v mpirun"], capture_output=True).returncode != 0
    or not built_with_mpi(), reason="rtcl built without MPI, or no mpirun")


def own_messages(stderr):
    """rtcl's messages under mpirun, less the other ranks' "interrupted" lines: a
    failing rank makes mpirun end the others, which may say so."""
    return [line for line in stderr.splitlines() if line.startswith("rtcl:")
            and not line.startswith("rtcl: interrupted; no output written")]


def mpi_run(*args, env=None):
    return subprocess.run([*MPIRUN, RTCL, "--mpi", *args], capture_output=True, text=True,
                          cwd=ROOT, timeout=300, env={**os.environ, **MPI_ENV, **(env or {})})


@needs_mpi
def test_mpi_frames_match_one_process_and_every_frame_is_written_once(tmp_path):
    ranks, single = tmp_path / "ranks", tmp_path / "single"
    ranks.mkdir()
    single.mkdir()
    result = mpi_run(*SMALL, "--frames", "0:7", "-o", str(ranks / "f.ppm"), "--stats",
                     str(ranks / "s.json"))
    assert result.returncode == 0, result.stderr
    frames_run(single, "--frames", "0:7", "-d", "0")
    stats = json.loads((ranks / "s.json").read_text())
    devices = stats["multidevice"]["devices"]
    assert sorted(d["rank"] for d in devices) == [0, 1, 2]
    assert sum(d["pieces"] for d in devices) == 8
    assert sum(d["pixels"] for d in devices) == 8 * 32 * 24
    for f in range(8):
        name = f"f_{f:04d}.ppm"
        assert (ranks / name).read_bytes() == (single / name).read_bytes(), name
    assert result.stdout.count("rank ") == 3


@needs_mpi
@pytest.mark.parametrize("scene, kernel", [
    (None, "dynamic"), pytest.param("random300.json", "persistent", marks=pytest.mark.slow),
    pytest.param("path_box.json", "wavefront", marks=pytest.mark.slow)])
def test_frames_on_kept_renderers_match_a_renderer_a_frame(tmp_path, scene, kernel):
    # --frames keeps each device's renderer open from frame to frame (issue
    # 43: opening one took 45-100 ms of a 2000x2000 frame's 190-240 on an
    # H100) and writes each frame's scene, packed for its eye, into it; the
    # ranks of --mpi still open one a frame (render()). Every frame the same
    # bytes, a renderer opened once a device.
    kept, fresh = tmp_path / "kept", tmp_path / "fresh"
    kept.mkdir()
    fresh.mkdir()
    args = [*SMALL, "--frames", "0:5", "-k", kernel]
    if scene:
        args += ["-s", str(ROOT / "test" / "scenes" / scene)]
    _, stats = frames_run(kept, *args, "--devices", "0:0,0:1")
    result = mpi_run(*args, "-o", str(fresh / "f.ppm"))
    assert result.returncode == 0, result.stderr
    for f in range(6):
        name = f"f_{f:04d}.ppm"
        assert (kept / name).read_bytes() == (fresh / name).read_bytes(), name
    devices = stats["multidevice"]["devices"]
    assert sum(d["pieces"] for d in devices) == 6
    assert all(d["renderers_opened"] == 1 for d in devices), devices


@needs_mpi
@pytest.mark.slow
@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="binding to one core of one is no note")
def test_mpi_ranks_bound_to_one_core_get_a_note_and_bands(tmp_path):
    """Open MPI binds one or two ranks to a core each by default, where a rank's
    BVH build and sums then run alone: rank 0 says so once, and GPUs alone
    (RTCL_TEST_AS_GPUS) split the image in bands; unbound, the devices'
    probes choose, as in one process (docs/results/multidevice/README.md,
    "MPI"). Both give the same image."""
    def run(binding):
        out = tmp_path / binding
        out.mkdir()
        rank = [RTCL, "--mpi", "--size", "16x8", "--spp", "256", "-k", "dynamic", "-o",
                str(out / "x.ppm"), "--stats", str(out / "s.json")]
        result = subprocess.run(["mpirun", "--bind-to", binding, "-np", "2", *rank],
                                capture_output=True, text=True, cwd=ROOT, timeout=300,
                                env={**os.environ, **MPI_ENV, "RTCL_TEST_AS_GPUS": "1"})
        assert result.returncode == 0, result.stderr
        md = json.loads((out / "s.json").read_text())["multidevice"]
        return result, (md["split"], md.get("split_choice")), (out / "x.ppm").read_bytes()
    (bound, bound_split, bound_image), (free, free_split, free_image) = run("core"), run("none")
    notes = [line for line in own_messages(bound.stderr) if line.startswith("rtcl: note:")]
    assert len(notes) == 1 and "bound 2 of 2 rank(s) to one core each" in notes[0], bound.stderr
    assert "--bind-to none" in notes[0]
    assert "rtcl: note:" not in free.stderr, free.stderr
    assert bound_split == ("dynamic", None)
    choice = free_split[1]
    cheap = choice["sums_ms"] + choice["add_ms"] <= choice["penalty_ms"]
    assert free_split[0] == ("samples" if cheap else "dynamic"), free_split
    assert bound_image == free_image


# The pieces of the MPI tests below: 9 frames, or one image in 12 bands of 2
# rows, with the pieces each of the 3 ranks' devices gets under --split static.
MPI_PIECES = {"frames": (["--frames", "0:8"], "f.ppm", 3),
              "bands": (["--piece-rows", "2"], "x.ppm", 4)}


@needs_mpi
@pytest.mark.parametrize("mode", MPI_PIECES)
def test_mpi_static_split_gives_every_rank_its_share(tmp_path, mode):
    pieces, output, share = MPI_PIECES[mode]
    result = mpi_run(*SMALL, *pieces, "--split", "static", "-o", str(tmp_path / output),
                     "--stats", str(tmp_path / "s.json"), env={"RTCL_TEST_SLOW_DEVICE": "0:50"})
    assert result.returncode == 0, result.stderr
    devices = json.loads((tmp_path / "s.json").read_text())["multidevice"]["devices"]
    assert [d["pieces"] for d in devices] == [share] * 3


@needs_mpi
@pytest.mark.parametrize("mode", MPI_PIECES)
def test_mpi_device_failure_on_a_rank_writes_nothing(tmp_path, mode):
    pieces, output, _ = MPI_PIECES[mode]
    result = mpi_run(*SMALL, *pieces, "-o", str(tmp_path / output),
                     env={"RTCL_TEST_FAIL_DEVICE": "0:2"})
    assert result.returncode == 1, result.stderr
    ours = own_messages(result.stderr)
    assert len(ours) == 1, result.stderr
    assert re.match(r"rtcl: rank \d, device 0:0 \(.*\): the device failed on its piece 2", ours[0])
    assert os.listdir(tmp_path) == []


# When a rank dies, mpirun's daemon sends the others SIGCONT, then SIGTERM
# after odls_base_sigkill_timeout (1 s), then SIGKILL after as long again; but
# a rank exiting on the SIGTERM cuts that sleep short (SIGKILL ~5 ms after),
# so rank 0 may be killed before its interrupt thread runs. A timeout of 0
# kills at once, every time: nothing may depend on rank 0 cleaning up.
HARD_KILL = {"OMPI_MCA_odls_base_sigkill_timeout": "0"}


@needs_mpi
@pytest.mark.parametrize("kill", ["term_then_kill", "kill_at_once"])
def test_mpi_rank_that_dies_fails_the_run_with_no_output(tmp_path, kill):
    env = {"RTCL_TEST_RANK_DIES": "2:2", **(HARD_KILL if kill == "kill_at_once" else {})}
    result = mpi_run(*SMALL, "--frames", "0:11", "-o", str(tmp_path / "f.ppm"), "--stats",
                     str(tmp_path / "s.json"), env=env)
    assert result.returncode != 0
    assert "rank 2" in result.stderr and "signal 9" in result.stderr, result.stderr
    if kill == "term_then_kill":  # some rank has the time to say so
        assert "no output written" in result.stderr
    assert os.listdir(tmp_path) == [], "a dead rank left files behind"


def mpmd_run(first, second, cwd=(ROOT, ROOT)):
    """Two ranks of different command lines (mpirun's app contexts)."""
    command = ["mpirun", "--oversubscribe", "-np", "1", "--wdir", str(cwd[0]), RTCL, "--mpi",
               *first, ":", "-np", "1", "--wdir", str(cwd[1]), RTCL, "--mpi", *second]
    return subprocess.run(command, capture_output=True, text=True, cwd=ROOT, timeout=120,
                          env={**os.environ, **MPI_ENV})


# Ranks that render different jobs (issue 24, finding 8) spliced one image
# from both with exit status 0, or failed with "internal error: piece 3 of 3".
@needs_mpi
@pytest.mark.parametrize("first, second, message", [
    (["-s", "scenes/two_balls.json"], ["-s", "scenes/paper60.json"],
     "rank 1 renders another job: the scene differs (file scenes/two_balls.json on rank 0, "
     "scenes/paper60.json on rank 1)"),
    ([], ["--spp", "4"], "rank 1 renders another job: --spp 4 against rank 0's --spp 1"),
    # The other settings go the same way: make test-long.
    pytest.param(["--frames", "0:1"], ["--frames", "0:2"],
                 "rank 1 renders another job: --frames 0:2 against rank 0's --frames 0:1",
                 marks=pytest.mark.slow),
    pytest.param([], ["--size", "64x24"],
                 "rank 1 renders another job: --size 64x24 against rank 0's --size 32x24",
                 marks=pytest.mark.slow),
    pytest.param(["--piece-rows", "2"], ["--piece-rows", "3"],
                 "rank 1 renders another job: --piece-rows 3 against rank 0's --piece-rows 2",
                 marks=pytest.mark.slow),
])
def test_mpi_ranks_that_render_different_jobs_are_refused(tmp_path, first, second, message):
    out = ["-o", str(tmp_path / "x.ppm"), "--stats", str(tmp_path / "s.json")]
    result = mpmd_run([*SMALL, *first, *out], [*SMALL, *second, *out])
    assert result.returncode == 1, result.stderr
    assert own_messages(result.stderr) == [f"rtcl: {message}"], result.stderr
    assert os.listdir(tmp_path) == []


@needs_mpi
def test_mpi_ranks_whose_scene_files_differ_in_content_are_refused(tmp_path):
    # The same name in two folders: the digest of the loaded scene tells.
    a, b, out = tmp_path / "a", tmp_path / "b", tmp_path / "out"
    for folder in (a, b, out):
        folder.mkdir()
    scene = json.loads((ROOT / "scenes" / "two_balls.json").read_text())
    (a / "s.json").write_text(json.dumps(scene))
    scene["spheres"][0]["radius"] *= 1.0000001
    (b / "s.json").write_text(json.dumps(scene))
    args = [*SMALL, "-s", "s.json", "-o", str(out / "x.ppm")]
    result = mpmd_run(args, args, cwd=(a, b))
    assert result.returncode == 1, result.stderr
    assert own_messages(result.stderr) == [
        "rtcl: rank 1 renders another job: the scene differs (file s.json on rank 0, s.json "
        "on rank 1, with other contents)"], result.stderr
    assert os.listdir(out) == []


# Ctrl-C to mpirun while rank 0 commits (issue 24, finding 15): mpirun sends
# SIGCONT, then SIGTERM some 30 ms later; rank 0 had finished and exited 0
# in between, and mpirun's status 1 came with no message at all, though
# every output was written. RTCL_TEST_COMMIT_DELAY holds rank 0 in its
# commit, after the renames, for the signal to come then.
@needs_mpi
def test_mpi_interrupt_while_rank_0_commits_says_the_outputs_were_written(tmp_path):
    command = [*MPIRUN[:-1], "2", RTCL, "--mpi", *SMALL, "-q", "--frames", "0:19", "-o",
               str(tmp_path / "f.ppm")]
    process = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True,
                               env={**os.environ, **MPI_ENV, "RTCL_TEST_COMMIT_DELAY": "300"})
    deadline = time.monotonic() + 120
    while (not any(name.startswith("f_") for name in os.listdir(tmp_path))
           and process.poll() is None and time.monotonic() < deadline):
        time.sleep(0.001)
    process.send_signal(signal.SIGINT)
    try:
        _, stderr = process.communicate(timeout=60)
    finally:
        process.kill()
    assert sorted(os.listdir(tmp_path)) == [f"f_{f:04d}.ppm" for f in range(20)]
    assert "rtcl: interrupted; the outputs were written\n" in stderr, stderr
    assert "no output written" not in stderr, stderr


@needs_mpi
def test_mpi_frames_that_do_not_fit_in_rank_0s_memory_are_refused(tmp_path):
    result = mpi_run("--size", "16384x16384", "--frames", "0:999", "-o",
                     str(tmp_path / "f.ppm"))
    assert result.returncode == 1, result.stderr
    ours = own_messages(result.stderr)
    assert len(ours) == 1, result.stderr
    assert re.match(r"rtcl: rank 0: --frames: under --mpi, rank 0 keeps every frame in host "
                    r"memory .*: 1000 frames of 16384x16384 need 3000\.0 GiB \(12 bytes a "
                    r"pixel\), more than the limit of [0-9.]+ GiB", ours[0]), ours[0]
    assert os.listdir(tmp_path) == []


def test_mpi_as_a_single_rank_renders_or_says_how_to_get_mpi(tmp_path):
    asan = {k: v for k, v in MPI_ENV.items() if k == "ASAN_OPTIONS"}  # see MPI_ENV
    result = run(*SMALL, "--mpi", "-o", str(tmp_path / "x.ppm"), env=asan)
    if "built without MPI" in result.stderr:
        assert result.returncode == 1
        assert os.listdir(tmp_path) == []
    else:  # a singleton MPI process: rank 0 alone
        assert result.returncode == 0, result.stderr
        assert (tmp_path / "x.ppm").exists()


def test_help_and_man_page_teach_the_options():
    help_text = run("--help").stdout
    man = (ROOT / "docs" / "rtcl.1").read_text()
    for option in ["--devices LIST|all", "--split dynamic|static|samples", "--frames A:B", "--mpi",
                   "out_0000.png", "--piece-rows N", "--row-order interleave[:S]|scan"]:
        assert option in help_text, option
    for option in [r"\-\-devices", r"\-\-split", r"\-\-frames", r"\-\-mpi",
                   r"\-\-piece\-rows", r"\-\-row\-order"]:
        assert option in man, option


# ---- one image in row bands over several devices (tiles.h) -----------------

CHECK = {"RTCL_TEST_CHECK_WRITES": "1"}  # every pixel written once, or the run fails
KERNELS = ["serial", "naive", "cyclic", "dynamic", "persistent", "wavefront"]


def image_run(directory, name, *args, env=None):
    stats = directory / f"{name}.json"
    result = run(*SMALL, "-o", str(directory / f"{name}.ppm"), "--stats", str(stats), *args,
                 env=env)
    assert result.returncode == 0, result.stderr
    return result, json.loads(stats.read_text())


# make test runs dynamic and the wavefront at 1 spp through the command line;
# the other kernels and 4 spp are in make test-long: Criterion's multidev tests
# check bands at 1 and 4 spp for every kernel in make test.
@pytest.mark.parametrize("spp", ["1", pytest.param("4", marks=pytest.mark.slow)])
@pytest.mark.parametrize("kernel", [kernel if kernel in ("dynamic", "wavefront")
                                    else pytest.param(kernel, marks=pytest.mark.slow)
                                    for kernel in KERNELS])
def test_bands_on_two_devices_match_one_device_byte_for_byte(tmp_path, kernel, spp):
    common = ["-k", kernel, "--spp", spp]
    image_run(tmp_path, "one", *common, "-p", "0", "-d", "0")
    _, stats = image_run(tmp_path, "two", *common, "--devices", "0:0,0:1", "--piece-rows", "4",
                         env=CHECK)
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "two.ppm").read_bytes()
    md = stats["multidevice"]
    assert md["piece"] == "band" and md["bands"] == 6 and md["band_rows"] == 4
    assert sum(d["pieces"] for d in md["devices"]) == 6
    assert sum(d["pixels"] for d in md["devices"]) == 32 * 24
    for d in md["devices"]:  # the kernels' share of the busy time
        assert d["launches"] >= d["pieces"]
        assert (d["kernel_ms"] > 0) == (d["pieces"] > 0)
        assert d["kernel_ms"] <= d["busy_ms"]


def test_bands_on_one_device_match_its_whole_image(tmp_path):
    # --devices P:D --piece-rows N renders one device's image in bands (what
    # pieces of N rows cost it), byte-identical to its whole-image render.
    image_run(tmp_path, "one", "--spp", "3", "-d", "0")
    _, stats = image_run(tmp_path, "bands", "--spp", "3", "--devices", "0:0", "--piece-rows",
                         "5", env=CHECK)
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "bands.ppm").read_bytes()
    md = stats["multidevice"]
    assert md["piece"] == "band" and md["bands"] == 5 and md["band_rows"] == 5
    [device] = md["devices"]
    assert device["pieces"] == 5 and device["pixels"] == 32 * 24
    assert md["device_efficiency"] == 1.0


# 12 bands of 4 rows (-w 8x4) to deal to the classes.
TALL = ["--size", "24x48", "-w", "8x4"]


def image_row(v, md):
    """Split row v's image row: rt_piece_row (cl/rtcl_shared.h) as
    docs/GUIDE.md states it, from the map --stats reports: the bands dealt
    to S classes, class after class, each top to bottom."""
    band, bands, classes = md["row_band"], md["row_bands"], md["row_classes"]
    if band == 0 or v >= band * bands:
        return v
    order = [b for c in range(classes) for b in range(c, bands, classes)]
    return order[v // band] * band + v % band


@pytest.mark.parametrize("order, pieces, classes", [
    ("interleave", [], 2), ("scan", [], 0), ("interleave:5", ["--piece-rows", "5"], 5),
    pytest.param("interleave", ["--split", "static", "--piece-rows", "8"], 2,
                 marks=pytest.mark.slow)])
def test_row_orders_match_one_device_and_their_pieces_cover_the_image_once(tmp_path, order,
                                                                           pieces, classes):
    common = [*TALL, "--spp", "2", "-k", "persistent"]
    one = run(*common, "-d", "0", "-o", str(tmp_path / "one.ppm"))
    assert one.returncode == 0, one.stderr
    result = run(*common, "--devices", "0:0,0:1", "--row-order", order, *pieces, "-o",
                 str(tmp_path / "two.ppm"), "--stats", str(tmp_path / "s.json"), env=CHECK)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "two.ppm").read_bytes()
    md = json.loads((tmp_path / "s.json").read_text())["multidevice"]
    assert md["row_order"] == order.split(":")[0]
    assert (md["row_band"], md["row_bands"], md["row_classes"]) == \
        ((4, 12, classes) if classes else (0, 0, 0))
    covered = [[0] * 24 for _ in range(48)]
    scattered = 0
    for p in md["pieces"]:
        rows = [image_row(v, md) for v in range(p["y0"], p["y0"] + p["height"])]
        scattered += rows != list(range(rows[0], rows[0] + len(rows)))
        for y in rows:
            for x in range(p["x0"], p["x0"] + p["width"]):
                covered[y][x] += 1
        assert 0 <= p["start_ms"] <= p["end_ms"] and p["kernel_ms"] > 0
        assert p["device"] in (0, 1)
    assert all(c == 1 for row in covered for c in row), covered
    assert (scattered > 0) == (classes > 0)


def test_interleaved_split_gives_a_slowed_device_less_of_the_image(tmp_path):
    # Issue 28's simulation of unequal devices: the default split (adaptive
    # rectangles of interleaved rows) over two PoCL devices, one slowed: it
    # renders fewer pixels, every pixel is written once, the image is one
    # device's.
    common = [*TALL, "--spp", "2"]
    one = run(*common, "-d", "0", "-o", str(tmp_path / "one.ppm"))
    assert one.returncode == 0, one.stderr
    result = run(*common, "--devices", "0:0,0:1", "-o", str(tmp_path / "two.ppm"), "--stats",
                 str(tmp_path / "s.json"), env={**CHECK, "RTCL_TEST_SLOW_DEVICE": "1:200"})
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "two.ppm").read_bytes()
    md = json.loads((tmp_path / "s.json").read_text())["multidevice"]
    assert md["row_order"] == "interleave" and md["row_classes"] == 2
    pixels = [d["pixels"] for d in md["devices"]]
    assert sum(pixels) == 24 * 48 and pixels[1] < pixels[0], pixels


@pytest.mark.parametrize("kernel, scene", [
    ("dynamic", "scenes/paper60.json"),
    pytest.param("persistent", "test/scenes/mirror_corridor.json", marks=pytest.mark.slow),
    pytest.param("wavefront", "test/scenes/mirror_corridor.json", marks=pytest.mark.slow)])
def test_sample_split_matches_one_device_byte_for_byte(tmp_path, kernel, scene):
    # --split samples: both devices render the whole image, each a range of
    # every pixel's samples into its fixed-point sums, which the host adds:
    # the image is one device's (RENDERING.md, "Samples per pixel"). The
    # mirror corridor has colours of every size; every pixel written once a
    # pass on each device (CHECK). make test's case builds the program the
    # next test uses.
    common = ["-k", kernel, "--spp", "6", "-s", scene]
    image_run(tmp_path, "one", *common, "-d", "0", env=CHECK)  # the same program
    _, stats = image_run(tmp_path, "two", *common, "--devices", "0:0,0:1", "--split", "samples",
                         env=CHECK)
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "two.ppm").read_bytes()
    md = stats["multidevice"]
    assert md["split"] == "samples" and md["piece"] == "sample range"
    assert [d["pieces"] for d in md["devices"]] == [1, 1]
    # Each piece the whole image and a range of the samples, one after the
    # other from 0 (--stats pieces: [begin, end)).
    ranges = sorted(p["samples"] for p in md["pieces"])
    assert ranges[0][0] == 0 and ranges[0][1] == ranges[1][0] and ranges[1][1] == 6, ranges
    assert all((p["width"], p["height"]) == (32, 24) for p in md["pieces"])
    assert "bands" not in md and "row_order" not in md
    # Each takes a share of the samples: pixels count that share.
    assert all(0 < d["pixels"] < 32 * 24 for d in md["devices"])
    assert abs(sum(d["pixels"] for d in md["devices"]) - 32 * 24) <= 1


@pytest.mark.slow
def test_sample_split_saturates_as_one_device(tmp_path):
    # Radiance that overflows float (lights, colours and kd of 1e18) saturates
    # the fixed-point sums: the host's sum of the devices' is saturated too
    # and written as the largest float, as one device writes it.
    from test_encoding import hot_scene  # noqa: E402 (test/ is on the path)
    common = ["-s", str(hot_scene(tmp_path)), "--size", "24x16", "--spp", "4"]
    one = run(*common, "-d", "0", "-o", str(tmp_path / "one.pfm"))
    assert one.returncode == 0, one.stderr
    two = run(*common, "--devices", "0:0,0:1", "--split", "samples", "-o",
              str(tmp_path / "two.pfm"))
    assert two.returncode == 0, two.stderr
    data = (tmp_path / "one.pfm").read_bytes()
    assert data == (tmp_path / "two.pfm").read_bytes()
    assert struct.pack("<f", 3.4028234663852886e38) in data  # FLT_MAX, little-endian


def test_sample_split_gives_a_slowed_device_fewer_samples(tmp_path):
    # After the warm-up frame the ranges follow the devices' rates: the
    # device slowed 4 times takes fewer samples. GPUs alone take the sample
    # split by default (RTCL_TEST_AS_GPUS: the PoCL devices count as GPUs).
    common = ["--size", "16x8", "--spp", "256"]  # long enough: the measured default splits samples
    one = run(*common, "-d", "0", "-o", str(tmp_path / "one.ppm"), env=CHECK)  # one program
    assert one.returncode == 0, one.stderr
    result = run(*common, "--devices", "0:0,0:1", "-r", "2", "-o", str(tmp_path / "two.ppm"),
                 "--stats", str(tmp_path / "s.json"),
                 env={**CHECK, "RTCL_TEST_SLOW_DEVICE": "1:x4", "RTCL_TEST_AS_GPUS": "1"})
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "two.ppm").read_bytes()
    md = json.loads((tmp_path / "s.json").read_text())["multidevice"]
    assert md["split"] == "samples"
    pixels = [d["pixels"] for d in md["devices"]]
    assert pixels[1] < pixels[0], pixels
    # A row order asked for asks for pieces of pixels.
    result = run(*common, "--devices", "0:0,0:1", "--row-order", "scan", "-o",
                 str(tmp_path / "rows.ppm"), "--stats", str(tmp_path / "rows.json"),
                 env={**CHECK, "RTCL_TEST_AS_GPUS": "1"})
    assert result.returncode == 0, result.stderr
    md = json.loads((tmp_path / "rows.json").read_text())["multidevice"]
    assert md["split"] == "dynamic" and md["row_order"] == "scan", md


def test_sample_split_needs_a_sample_per_device(tmp_path):
    result = run(*SMALL, "--devices", "0:0,0:1", "--split", "samples", "-o",
                 str(tmp_path / "x.png"))
    expect_failure(result, 1, "--split samples shares each pixel's samples between the 2 "
                   "devices: it needs at least 2 samples per pixel (--spp or image.samples), "
                   "and this render has 1", tmp_path)


def test_write_count_check_catches_a_band_written_twice(tmp_path):
    # The hook's own check: a band rendered again on a second device (the
    # test-only RTCL_TEST_DOUBLE_BAND) must fail the run, naming the pixel.
    result = run(*SMALL, "--devices", "0:0,0:1", "-o", str(tmp_path / "x.ppm"),
                 env={**CHECK, "RTCL_TEST_DOUBLE_BAND": "1"})
    expect_failure(result, 1, "written 2 times, not 1", tmp_path)


def test_bands_with_repeats_work_map_and_static_split(tmp_path):
    image_run(tmp_path, "one", "--spp", "2", "-d", "0", "--work-map", str(tmp_path / "one.npy"))
    result, stats = image_run(tmp_path, "two", "--spp", "2", "--devices", "all", "--split",
                              "static", "-r", "3", "--work-map", str(tmp_path / "two.npy"),
                              env=CHECK)
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "two.ppm").read_bytes()
    # Per-pixel flops assemble like the image.
    assert (tmp_path / "one.npy").read_bytes() == (tmp_path / "two.npy").read_bytes()
    assert stats["repeat"] == 3 and len(stats["kernel_ms_all"]) == 3
    # Over several devices a frame's time is its wall time: the two agree.
    assert stats["frame_ms_all"] == stats["kernel_ms_all"]
    assert stats["multidevice"]["split"] == "static"
    assert "median of 3" in result.stdout and "device-level efficiency" in result.stdout
    assert result.stdout.count(" bands, ") + result.stdout.count(" band, ") == 2


def test_dynamic_split_gives_a_slow_device_fewer_bands(tmp_path):
    _, stats = image_run(tmp_path, "x", "--devices", "0:0,0:1", "--piece-rows", "2",
                         env={"RTCL_TEST_SLOW_DEVICE": "1:300"})
    pieces = [d["pieces"] for d in stats["multidevice"]["devices"]]
    assert sum(pieces) == 12
    assert pieces[1] < pieces[0], pieces


def test_static_split_gives_a_slow_device_its_share_of_bands(tmp_path):
    _, stats = image_run(tmp_path, "x", "--devices", "0:0,0:1", "--piece-rows", "2", "--split",
                         "static", env={"RTCL_TEST_SLOW_DEVICE": "1:50"})
    assert [d["pieces"] for d in stats["multidevice"]["devices"]] == [6, 6]


def test_a_device_failing_on_a_band_writes_nothing(tmp_path):
    # A static split, so that device 0 surely gets a second band: adaptively, a
    # slow run (the SAN build in CI) once gave device 1 every band but one.
    result = run(*SMALL, "--devices", "0:0,0:1", "--piece-rows", "2", "--split", "static", "-o",
                 str(tmp_path / "x.png"), "--stats", str(tmp_path / "s.json"),
                 "--work-map", str(tmp_path / "w.png"), env={"RTCL_TEST_FAIL_DEVICE": "0:2"})
    expect_failure(result, 1, "device 0:0 (", tmp_path)
    assert "failed on its piece 2" in result.stderr


@needs_mpi
@pytest.mark.parametrize("spp", ["1", "4"])
def test_mpi_bands_match_one_process_and_every_pixel_is_written_once(tmp_path, spp):
    # (test_mpi_interleaved_bands_match_one_process: bands that the row
    # order moves)
    image_run(tmp_path, "one", "--spp", spp, "-d", "0", "-k", "persistent")
    # 4 spp on two queues a device (--queues 2): the same image
    queues = ["--queues", "2"] if spp == "4" else []
    result = mpi_run(*SMALL, "--spp", spp, "-k", "persistent", "--piece-rows", "3", *queues, "-o",
                     str(tmp_path / "ranks.ppm"), "--stats", str(tmp_path / "s.json"),
                     env=CHECK)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "ranks.ppm").read_bytes()
    md = json.loads((tmp_path / "s.json").read_text())["multidevice"]
    assert sorted(d["rank"] for d in md["devices"]) == [0, 1, 2]
    assert md["bands"] == 8 and md["ranks"] == 3
    assert sum(d["pieces"] for d in md["devices"]) == 8
    assert sum(d["pixels"] for d in md["devices"]) == 32 * 24


@needs_mpi
def test_mpi_gpus_alone_take_a_class_each_under_the_dynamic_split(tmp_path):
    # GPUs alone (RTCL_TEST_AS_GPUS: the PoCL devices report as GPUs) take one
    # band per device, a class each, as --split static gives them: smaller
    # bands starved two H200s (6.57 s against 1.16 s). With CPUs, about 32
    # bands per device: 48 rows in bands of 4 (the work-group's height).
    common = [*TALL, "-k", "persistent"]
    one = run(*common, "-d", "0", "-o", str(tmp_path / "one.ppm"))
    assert one.returncode == 0, one.stderr
    for gpus, bands in (("1", 3), ("0", 12)):
        result = mpi_run(*common, "-o", str(tmp_path / f"ranks{gpus}.ppm"), "--stats",
                         str(tmp_path / f"s{gpus}.json"),
                         env={**CHECK, "RTCL_TEST_AS_GPUS": gpus})
        assert result.returncode == 0, result.stderr
        assert (tmp_path / "one.ppm").read_bytes() == \
            (tmp_path / f"ranks{gpus}.ppm").read_bytes()
        md = json.loads((tmp_path / f"s{gpus}.json").read_text())["multidevice"]
        assert md["split"] == "dynamic" and md["bands"] == bands, md
        assert sum(d["pieces"] for d in md["devices"]) == bands
        assert md["row_classes"] == 3


@needs_mpi
@pytest.mark.slow  # --split samples itself: test_sample_split_matches_one_device_byte_for_byte
def test_mpi_sample_split_matches_one_device(tmp_path):
    # --split samples over three ranks: every rank renders the whole image, a
    # third of the samples in whole passes, and sends its sums to rank 0,
    # which adds them: one device's image, every pixel written once a pass
    # on each (CHECK).
    common = ["--size", "16x8", "--spp", "12", "-k", "dynamic"]
    one = run(*common, "-d", "0", "-o", str(tmp_path / "one.ppm"))
    assert one.returncode == 0, one.stderr
    result = mpi_run(*common, "--split", "samples", "-o", str(tmp_path / "ranks.ppm"),
                     "--stats", str(tmp_path / "s.json"), env=CHECK)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "ranks.ppm").read_bytes()
    md = json.loads((tmp_path / "s.json").read_text())["multidevice"]
    assert md["split"] == "samples" and md["piece"] == "sample range", md
    assert [d["pieces"] for d in md["devices"]] == [1, 1, 1]
    assert sorted(d["rank"] for d in md["devices"]) == [0, 1, 2]
    assert abs(sum(d["pixels"] for d in md["devices"]) - 16 * 8) <= 2


@needs_mpi
@pytest.mark.parametrize("messages", ["0", "1"])
def test_mpi_ranks_sums_add_up_to_one_devices_image(tmp_path, messages):
    # The sample split's sums are added over the ranks: in the node's shared
    # memory, each rank a third of the pixels (every rank on one node), or by
    # MPI_Reduce in a tree (RTCL_TEST_SUMS_BY_MESSAGES, as across nodes).
    # Radiance that overflows float saturates the fixed-point sums: the
    # saturation marks are joined, not added, so the image is one device's,
    # the saturated channels written as the largest float.
    from test_encoding import hot_scene  # noqa: E402 (test/ is on the path)
    common = ["-s", str(hot_scene(tmp_path)), "--size", "24x16", "--spp", "6", "-k", "dynamic"]
    one = run(*common, "-d", "0", "-o", str(tmp_path / "one.pfm"))
    assert one.returncode == 0, one.stderr
    result = mpi_run(*common, "--split", "samples", "-o", str(tmp_path / "ranks.pfm"),
                     "--stats", str(tmp_path / "s.json"),
                     env={**CHECK, "RTCL_TEST_SUMS_BY_MESSAGES": messages})
    assert result.returncode == 0, result.stderr
    data = (tmp_path / "one.pfm").read_bytes()
    assert data == (tmp_path / "ranks.pfm").read_bytes()
    assert struct.pack("<f", 3.4028234663852886e38) in data  # FLT_MAX, little-endian
    md = json.loads((tmp_path / "s.json").read_text())["multidevice"]
    assert md["split"] == "samples" and md["ranks"] == 3
    assert sorted(d["rank"] for d in md["devices"]) == [0, 1, 2]
    added_by = {"0": "shared memory", "1": "MPI_Reduce"}[messages]
    assert md["rank_sums"]["added_by"] == added_by and md["rank_sums"]["ms"] >= 0


@needs_mpi
@pytest.mark.parametrize("slow_sums, split", [
    ("0", "samples"), pytest.param("4000", "dynamic", marks=pytest.mark.slow)])
def test_mpi_default_split_is_measured_over_the_ranks(tmp_path, slow_sums, split):
    # GPUs alone (RTCL_TEST_AS_GPUS) split the samples by default only when
    # the devices' probes, exchanged by the ranks, say that reading back and
    # adding the sums costs less than a share of the pixels would
    # (tiles_prefer_samples, as in one process); a read-back 4 s slower at
    # set-up (RTCL_TEST_SLOW_SUMS) makes it the bands (1 s was too little on
    # a loaded 2-core host, where the passes' host time, counted against the
    # bands since batch 100, came to over 1 s). Before, a fixed 128
    # samples a device chose. Every rank decides alike; one device's image,
    # every pixel written once a pass, the probe's included (CHECK).
    common = ["--size", "48x32", "--spp", "256", "-k", "dynamic"]
    one = run(*common, "-d", "0", "-o", str(tmp_path / "one.ppm"))
    assert one.returncode == 0, one.stderr
    result = mpi_run(*common, "-o", str(tmp_path / "ranks.ppm"), "--stats",
                     str(tmp_path / "s.json"),
                     env={**CHECK, "RTCL_TEST_AS_GPUS": "1", "RTCL_TEST_SLOW_SUMS": slow_sums})
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "ranks.ppm").read_bytes()
    md = json.loads((tmp_path / "s.json").read_text())["multidevice"]
    choice = md["split_choice"]
    if split == "samples" and choice["sums_ms"] + choice["add_ms"] > choice["penalty_ms"]:
        split = "dynamic"  # this busy 2-core host's timings chose the bands after all
    assert md["split"] == split, md
    assert choice["pass_ms"] > 0 and choice["sums_ms"] > 0 and choice["add_ms"] > 0
    # The pixel split's pieces travel to rank 0 by messages, timed at set-up
    # and counted against it (issue 43, batch 99: four H100 ranks' bands of
    # the box took 33-40 ms to reach rank 0), beside 4.8 % of the image's
    # time and its passes' host time.
    assert choice["move_ms"] > 0 and choice["overhead_ms"] >= 0, choice
    assert abs(choice["penalty_ms"] - 0.048 * choice["render_ms"] - choice["overhead_ms"] -
               choice["move_ms"]) < 1e-6 * max(choice["penalty_ms"], 1), choice
    if split == "samples":
        assert choice["sums_ms"] + choice["add_ms"] <= choice["penalty_ms"], choice
        assert md["rank_sums"]["added_by"] == "shared memory"
        assert [d["pieces"] for d in md["devices"]] == [1, 1, 1]
    else:
        assert choice["sums_ms"] >= 4000 > choice["penalty_ms"], choice
        assert "rank_sums" not in md and md["piece"] == "band"
        assert sum(d["pixels"] for d in md["devices"]) == 48 * 32
    assert "split:   " + split + ", measured:" in result.stdout


PATH_BOX = str(ROOT / "test" / "scenes" / "path_box.json")


def measured_split(md):
    """The split a default render's measurement chose, checked against its
    figures (tiles_prefer_samples): the samples when reading back and adding
    the sums costs no more than a share of the pixels would."""
    choice = md["split_choice"]
    assert choice["pass_ms"] > 0 and choice["sums_ms"] > 0 and choice["add_ms"] > 0
    cheap = choice["sums_ms"] + choice["add_ms"] <= choice["penalty_ms"]
    assert md["split"] == ("samples" if cheap else "dynamic"), md
    return md["split"]


# make test keeps the cheaper dynamic case (7 s against 13 cold); the
# wavefront case, which found the probe's write count, runs in make test-long.
@pytest.mark.parametrize("kernel", [pytest.param("wavefront", marks=pytest.mark.slow), "dynamic"])
def test_path_traced_default_split_is_measured_and_gives_one_devices_image(tmp_path, kernel):
    # A path-traced scene over two devices taken as GPUs (issue 43): the
    # split is chosen by the devices' probes as for Whitted scenes, and the
    # image is one device's, every pixel written once a pass (CHECK).
    common = ["-s", PATH_BOX, "--size", "24x16", "--spp", "8", "-k", kernel]
    image_run(tmp_path, "one", *common, "-d", "0")
    _, stats = image_run(tmp_path, "two", *common, "--devices", "0:0,0:1",
                         env={**CHECK, "RTCL_TEST_AS_GPUS": "1"})
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "two.ppm").read_bytes()
    measured_split(stats["multidevice"])


@needs_mpi
@pytest.mark.parametrize("kernel", ["wavefront", pytest.param("dynamic", marks=pytest.mark.slow)])
def test_mpi_path_traced_default_split_is_measured_and_gives_one_devices_image(tmp_path,
                                                                                kernel):
    # The same over three ranks. A wavefront pass is several launches but
    # one write of each pixel: the probe's writes were counted as its
    # launches, and the ranks' check (CHECK) failed "written 1 times, not 8".
    common = ["-s", PATH_BOX, "--size", "24x16", "--spp", "8", "-k", kernel]
    one = run(*common, "-d", "0", "-o", str(tmp_path / "one.ppm"))
    assert one.returncode == 0, one.stderr
    result = mpi_run(*common, "-o", str(tmp_path / "ranks.ppm"), "--stats",
                     str(tmp_path / "s.json"), env={**CHECK, "RTCL_TEST_AS_GPUS": "1"})
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "ranks.ppm").read_bytes()
    md = json.loads((tmp_path / "s.json").read_text())["multidevice"]
    if measured_split(md) == "samples":
        assert md["rank_sums"]["added_by"] == "shared memory" and md["rank_sums"]["ms"] >= 0


@needs_mpi
@pytest.mark.parametrize("way, split", [
    (None, "samples"), pytest.param("read", "samples", marks=pytest.mark.slow),
    pytest.param("host-ptr", None, marks=pytest.mark.slow),
    pytest.param("copy", "samples", marks=pytest.mark.slow)])
def test_mpi_ranks_sums_reach_the_shared_memory_each_way(tmp_path, way, split):
    # RTCL_MPI_SUMS: how a rank of one device puts its device's sums into
    # its slot of the node's shared memory (issue 43, batch 100: four H100
    # ranks' copies from pinned memory ended the frame 10-12 ms after the
    # devices): copied from a pinned read-back (the default), read straight
    # into the slot, or through a buffer made on the slot
    # (CL_MEM_USE_HOST_PTR, the default since batch 103: way None leaves
    # RTCL_MPI_SUMS unset). Each way gives one device's image, --split
    # samples or the measured default (split None: the probe's sums pass
    # through the slot's buffer before the clock, and the frame's replace
    # them), and --stats says which way ran.
    common = ["-s", PATH_BOX, "--size", "24x16", "--spp", "8", "-k", "dynamic"]
    one = run(*common, "-d", "0", "-o", str(tmp_path / "one.ppm"))
    assert one.returncode == 0, one.stderr
    given = ["--split", split] if split else []
    result = mpi_run(*common, *given, "-o", str(tmp_path / "ranks.ppm"), "--stats",
                     str(tmp_path / "s.json"),
                     env={**CHECK, "RTCL_TEST_AS_GPUS": "1",
                          **({"RTCL_MPI_SUMS": way} if way else {})})
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "ranks.ppm").read_bytes()
    md = json.loads((tmp_path / "s.json").read_text())["multidevice"]
    if split or measured_split(md) == "samples":
        assert md["rank_sums"] == {"added_by": "shared memory", "ms": md["rank_sums"]["ms"],
                                   "into_slot": way or "host-ptr"}, md


@needs_mpi
def test_mpi_sums_way_must_be_known(tmp_path):
    result = mpi_run(*SMALL, "--split", "samples", "-o", str(tmp_path / "x.ppm"),
                     env={"RTCL_MPI_SUMS": "pinned"})
    assert result.returncode == 2, result.stderr
    assert own_messages(result.stderr) == [
        "rtcl: RTCL_MPI_SUMS=pinned: expected copy, read or host-ptr (how --mpi's ranks put "
        "their sample sums into the node's shared memory), or leave it unset"]
    assert os.listdir(tmp_path) == []


@needs_mpi
@pytest.mark.slow  # the message itself: test_sample_split_needs_a_sample_per_device
def test_mpi_sample_split_needs_a_sample_per_device(tmp_path):
    result = mpi_run(*SMALL, "--split", "samples", "--spp", "2", "-o", str(tmp_path / "x.ppm"))
    assert result.returncode == 2, result.stderr
    assert own_messages(result.stderr) == [
        "rtcl: --split samples shares each pixel's samples between the 3 devices: it needs "
        "at least 3 samples per pixel (--spp or image.samples), and this render has 2"]
    assert os.listdir(tmp_path) == []


@needs_mpi
@pytest.mark.parametrize("order", ["interleave", pytest.param("scan", marks=pytest.mark.slow)])
def test_mpi_interleaved_bands_match_one_process(tmp_path, order):
    # Bands of split rows go to rank 0 packed, in split-row order, and are
    # placed by the row map: the image is the one process's. The classes are
    # every rank's devices, 3.
    common = [*TALL, "-k", "persistent"]
    one = run(*common, "-d", "0", "-o", str(tmp_path / "one.ppm"))
    assert one.returncode == 0, one.stderr
    result = mpi_run(*common, "--piece-rows", "5", "--row-order", order, "-o",
                     str(tmp_path / "ranks.ppm"), "--stats", str(tmp_path / "s.json"), env=CHECK)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "ranks.ppm").read_bytes()
    md = json.loads((tmp_path / "s.json").read_text())["multidevice"]
    assert md["row_order"] == order and md["bands"] == 10
    assert md["row_classes"] == (3 if order == "interleave" else 0)
    assert sum(d["pixels"] for d in md["devices"]) == 24 * 48


@needs_mpi
@pytest.mark.parametrize("kill", ["term_then_kill", "kill_at_once"])
def test_mpi_rank_that_dies_mid_image_fails_the_run_with_no_output(tmp_path, kill):
    env = {"RTCL_TEST_RANK_DIES": "1:2", **(HARD_KILL if kill == "kill_at_once" else {})}
    result = mpi_run(*SMALL, "--piece-rows", "1", "-o", str(tmp_path / "x.ppm"), "--stats",
                     str(tmp_path / "s.json"), env=env)
    assert result.returncode != 0
    assert "rank 1" in result.stderr and "signal 9" in result.stderr, result.stderr
    if kill == "term_then_kill":
        assert "no output written" in result.stderr
    assert os.listdir(tmp_path) == [], "a dead rank left files behind"


# ---- adaptive pieces: the default for one image over several devices --------

MEDIUM = ["--size", "96x64"]


# The split is the host's and the same for every kernel; each kernel's handling
# of pieces is checked in make test by test_kernels.c (check_pieces). Here the
# stack walk's dynamic and the wavefront's own passes in make test, the other
# four in make test-long.
@pytest.mark.parametrize("kernel", [k if k in ("dynamic", "wavefront")
                                    else pytest.param(k, marks=pytest.mark.slow)
                                    for k in KERNELS])
def test_adaptive_rectangles_match_one_device_byte_for_byte(tmp_path, kernel):
    common = [*MEDIUM, "-k", kernel, "--spp", "4"]
    image_run(tmp_path, "one", *common, "-p", "0", "-d", "0")
    # The slow device makes the pieces differ in size and shape (probe,
    # guided, partial cell rows): every pixel still written once (CHECK).
    _, stats = image_run(tmp_path, "two", *common, "--devices", "0:0,0:1",
                         env={**CHECK, "RTCL_TEST_SLOW_DEVICE": "1:x4"})
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "two.ppm").read_bytes()
    md = stats["multidevice"]
    assert md["piece"] == "rectangle" and md["split"] == "dynamic"
    assert "bands" not in md
    assert sum(d["pixels"] for d in md["devices"]) == 96 * 64
    assert all(d["pieces"] >= 1 for d in md["devices"])


def test_adaptive_rectangles_on_two_queues_each_match_one_device(tmp_path):
    # --queues 2: each piece's columns in two parts on two queues of its
    # device, launches alternating; every pixel still written once a pass.
    common = [*MEDIUM, "-k", "persistent", "--spp", "4"]
    image_run(tmp_path, "one", *common, "-p", "0", "-d", "0")
    _, stats = image_run(tmp_path, "two", *common, "--devices", "0:0,0:1", "--queues", "2",
                         "-r", "2", env={**CHECK, "RTCL_TEST_SLOW_DEVICE": "1:x4"})
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "two.ppm").read_bytes()
    assert stats["queues"] == 2
    md = stats["multidevice"]
    # Two launches a pass for a piece of two work-groups' width or more (one
    # for a piece of a single cell), their time counted once.
    for d in md["devices"]:
        assert d["launches"] >= d["pieces"]
        assert d["kernel_ms"] <= d["busy_ms"]
    assert sum(d["launches"] for d in md["devices"]) > sum(d["pieces"] for d in md["devices"])


def test_adaptive_repeats_and_work_map_match_one_device(tmp_path):
    image_run(tmp_path, "one", *MEDIUM, "--spp", "2", "-d", "0", "--work-map",
              str(tmp_path / "one.npy"))
    _, stats = image_run(tmp_path, "two", *MEDIUM, "--spp", "2", "--devices", "all", "-r", "3",
                         "--work-map", str(tmp_path / "two.npy"), env=CHECK)
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "two.ppm").read_bytes()
    assert (tmp_path / "one.npy").read_bytes() == (tmp_path / "two.npy").read_bytes()
    assert stats["multidevice"]["piece"] == "rectangle"


def test_adaptive_fifty_times_slower_device_takes_a_small_share(tmp_path):
    # RTCL_TEST_SLOW_DEVICE=1:x50: device 1 takes 50 times as long for each
    # piece as it really did. It gets a small probe, then the tail rule
    # retires it: a few pieces and a small share, the fast device the rest
    # (the makespan bound itself is the unit test
    # multidev/adaptive_gpu_and_cpu_finish_no_later_than_the_gpu_alone).
    _, stats = image_run(tmp_path, "x", "--size", "128x96", "--spp", "4", "--devices",
                         "0:0,0:1", env={**CHECK, "RTCL_TEST_SLOW_DEVICE": "1:x50"})
    fast, slow = stats["multidevice"]["devices"]
    assert fast["pixels"] + slow["pixels"] == 128 * 96
    assert 1 <= slow["pieces"] <= 3, (fast, slow)
    assert fast["pieces"] > slow["pieces"], (fast, slow)
    assert slow["pixels"] <= 0.1 * 128 * 96, (fast, slow)
    # The slow device's last piece began before the fast one was done.
    assert slow["finish_ms"] - slow["last_piece_ms"] <= fast["finish_ms"] + 1


def test_piece_rows_keeps_fixed_bands(tmp_path):
    _, stats = image_run(tmp_path, "x", *MEDIUM, "--devices", "0:0,0:1", "--piece-rows", "8",
                         env=CHECK)
    md = stats["multidevice"]
    assert md["piece"] == "band" and md["bands"] == 8 and md["band_rows"] == 8
    assert sum(d["pieces"] for d in md["devices"]) == 8


FOUR = {"POCL_DEVICES": "pthread pthread pthread pthread"}


def test_default_split_over_four_devices_is_measured_and_matches_one_device(tmp_path):
    # Issue 43: four GPUs (RTCL_TEST_AS_GPUS: PoCL's devices count as GPUs)
    # split the samples by default when the devices' probes at set-up say
    # that the read-back of their sums costs less than a share of the
    # pixels would (tiles_prefer_samples), their add on the host included.
    # Every pixel written once a pass, the probe's pass included (CHECK).
    common = ["--size", "48x32", "--spp", "256"]
    one = run(*common, "-d", "0", "-o", str(tmp_path / "one.ppm"))
    assert one.returncode == 0, one.stderr
    result = run(*common, "--devices", "0:0,0:1,0:2,0:3", "-o", str(tmp_path / "four.ppm"),
                 "--stats", str(tmp_path / "s.json"),
                 env={**FOUR, **CHECK, "RTCL_TEST_AS_GPUS": "1"})
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "four.ppm").read_bytes()
    md = json.loads((tmp_path / "s.json").read_text())["multidevice"]
    choice = md["split_choice"]
    assert md["split"] == "samples" and md["piece"] == "sample range", md
    assert choice["sums_ms"] > 0 and choice["add_ms"] > 0
    assert choice["sums_ms"] + choice["add_ms"] <= choice["penalty_ms"], choice
    assert choice["pass_samples"] >= 1 and choice["pass_ms"] > 0
    assert choice["render_ms"] > 0
    # The pixel split's cost: 4.8 % of the image's time, plus its passes'
    # host time beyond their kernels that each device pays whole (issue 43,
    # batch 99: a wavefront's round trips); nothing to move to a rank 0.
    assert choice["overhead_ms"] >= 0 and choice["move_ms"] == 0, choice
    assert abs(choice["penalty_ms"] - 0.048 * choice["render_ms"] - choice["overhead_ms"]) < \
        1e-6 * choice["render_ms"], choice
    assert sorted(p["samples"] for p in md["pieces"]) == [[0, 64], [64, 128], [128, 192],
                                                           [192, 256]]
    assert "split:   samples, measured:" in result.stdout


def test_a_slow_read_back_of_the_sums_makes_the_default_split_the_pixels(tmp_path):
    # The same render with every device's read-back of its sums 1 s slower
    # at set-up (RTCL_TEST_SLOW_SUMS): a share of the pixels costs less, so
    # the devices take rectangles of all the samples (the dynamic split).
    common = ["--size", "48x32", "--spp", "16"]
    one = run(*common, "-d", "0", "-o", str(tmp_path / "one.ppm"))
    assert one.returncode == 0, one.stderr
    result = run(*common, "--devices", "0:0,0:1,0:2,0:3", "-o", str(tmp_path / "four.ppm"),
                 "--stats", str(tmp_path / "s.json"),
                 env={**FOUR, **CHECK, "RTCL_TEST_AS_GPUS": "1", "RTCL_TEST_SLOW_SUMS": "1000"})
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "one.ppm").read_bytes() == (tmp_path / "four.ppm").read_bytes()
    md = json.loads((tmp_path / "s.json").read_text())["multidevice"]
    choice = md["split_choice"]
    assert md["split"] == "dynamic" and md["piece"] == "rectangle", md
    assert choice["sums_ms"] >= 1000 > choice["penalty_ms"], choice
    assert all(p["samples"] == [0, 16] for p in md["pieces"])
    assert sum(d["pixels"] for d in md["devices"]) == 48 * 32


def test_split_given_or_cpus_are_not_measured(tmp_path):
    # A split asked for, or devices that are not all GPUs, take no probe.
    for args, env in [(["--split", "samples"], {"RTCL_TEST_AS_GPUS": "1"}),
                      (["--split", "dynamic"], {"RTCL_TEST_AS_GPUS": "1"}), ([], {})]:
        result = run("--size", "16x8", "--spp", "8", "--devices", "0:0,0:1", *args, "-o",
                     str(tmp_path / "x.ppm"), "--stats", str(tmp_path / "s.json"), env=env)
        assert result.returncode == 0, result.stderr
        md = json.loads((tmp_path / "s.json").read_text())["multidevice"]
        assert "split_choice" not in md, (args, md)
        assert "measured" not in result.stdout


def test_sample_split_over_four_devices_that_fail_writes_nothing_and_ends(tmp_path):
    # Every device fails its launches (RTCL_TEST_DEVICE_FAULT) before its
    # sums are read: the run fails with one message and no output.
    result = run("--size", "48x32", "--spp", "8", "--devices", "0:0,0:1,0:2,0:3", "--split",
                 "samples", "-o", str(tmp_path / "x.ppm"),
                 env={**FOUR, "RTCL_TEST_DEVICE_FAULT": "1"})
    expect_failure(result, 1, "device 0:", tmp_path)
