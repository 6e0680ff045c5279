"""Nothing lost, part 2 (issue 24): no output replaces an input; a commit
replaces every target or none; the RTCL_DUMP_BINARY program is an output like
the others; a killed run's staged files are removed by the next run; a
symbolic link is written through. Every test here failed on commit 2831c66
(before the staging folders and the all-or-nothing commit) and passes since,
but two that guard the new design: a live run's staging folder is left alone,
and the RTCL_DUMP_BINARY program is committed with an animation's frames.
"""
import os
import pathlib
import shutil
import signal
import subprocess
import time

import pytest

import builds

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
SMALL = ["--size", "24x16", "-q"]
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "POCL_DEVICES": "pthread", "OMPI_MCA_btl": "self,vader,tcp",
           "OMPI_MCA_orte_tmpdir_base": builds.ompi_session_base()}
if "ASAN_OPTIONS" in os.environ:  # as in test_multidev.py
    MPI_ENV["ASAN_OPTIONS"] = os.environ["ASAN_OPTIONS"] + ":detect_leaks=0"
PREVIOUS = b"the user's previous file"


def rtcl(*args, cwd, env=None):
    return subprocess.run([RTCL, *args], capture_output=True, text=True, cwd=cwd, timeout=120,
                          env={**os.environ, **(env or {})})


def expect_refused(result, status, message):
    assert result.returncode == status, (result.returncode, result.stderr)
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert message in lines[0], lines[0]


def listing(folder):
    return sorted(os.listdir(folder))


def staged(folder, name):
    """Whether the render has staged `name` in folder: a file for it, not
    empty, in a staging folder (.rtcl-stage-HOST-PID) or, as rtcl staged
    before, as .NAME.tmp-*. (The checks before the render create an empty one
    for a moment.)"""
    candidates = []
    for entry in os.listdir(folder):
        if entry.startswith(f".{name}.tmp-"):
            candidates.append(folder / entry)
        if entry.startswith(".rtcl-stage-"):
            try:
                candidates += [folder / entry / inner for inner in os.listdir(folder / entry)
                               if name in inner]
            except FileNotFoundError:
                pass
    for path in candidates:
        try:
            if path.stat().st_size > 0:
                return True
        except FileNotFoundError:
            pass
    return False


def wait_for(condition, process, seconds=60):
    deadline = time.monotonic() + seconds
    while not condition() and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.005)
    assert condition(), "the moment never came"


@pytest.fixture
def scene(tmp_path):
    """A scene file with a mesh file beside it, in tmp_path."""
    shutil.copy(ROOT / "test" / "meshes" / "cube.obj", tmp_path / "cube.obj")
    (tmp_path / "s.json").write_text(
        '{"format": "rtcl-scene", "version": 2,'
        ' "camera": {"eye": [0, 3, -8], "look_at": [0, 1, 0], "fov": 45},'
        ' "lights": [{"position": [-10, 20, -10], "color": [1, 1, 1]}],'
        ' "meshes": [{"file": "cube.obj"}]}')
    os.link(tmp_path / "s.json", tmp_path / "hard.json")
    (tmp_path / "link.json").symlink_to("s.json")
    return tmp_path


# ---- 1. an output may not replace an input ---------------------------------

INPUT_CLASHES = {
    "stats is the scene": (["-o", "o.png", "--stats", "s.json"], "--stats s.json names the "
                           "scene file s.json"),
    "stats is a hard link to the scene": (["-o", "o.png", "--stats", "hard.json"],
                                          "--stats hard.json names the scene file s.json"),
    "stats is a symbolic link to the scene": (["-o", "o.png", "--stats", "./link.json"],
                                              "--stats ./link.json names the scene file"),
    "stats is the mesh": (["-o", "o.png", "--stats", "./cube.obj"],
                          "--stats ./cube.obj names the mesh file cube.obj"),
    "the flops sidecar is the scene": (["-o", "o.png", "--flops", "s.json.npy"], None),
    "the image is the scene": (["-o", "./s.png"], "-o/--output ./s.png names the scene file "
                               "s.png"),
    "a frame is the scene": (["--frames", "1:2", "-o", "s.png"], "frame 2's image s_0002.png "
                             "names the scene file"),
    "stats of frames is the mesh": (["--frames", "1:2", "-o", "f.png", "--stats", "cube.obj"],
                                    "--stats cube.obj names the mesh file cube.obj"),
}


@pytest.mark.parametrize("case", INPUT_CLASHES)
def test_an_output_naming_an_input_is_refused_before_rendering(scene, case):
    options, message = INPUT_CLASHES[case]
    scene_file = "s.json"
    if case == "the flops sidecar is the scene":
        shutil.copy(scene / "s.json", scene / "s.json.npy.json")
        scene_file = "s.json.npy.json"
        message = "--flops (its sidecar) s.json.npy.json names the scene file s.json.npy.json"
    if case == "a frame is the scene":
        shutil.copy(scene / "s.json", scene / "s_0002.png")
        scene_file = "s_0002.png"
    if case == "the image is the scene":
        shutil.copy(scene / "s.json", scene / "s.png")
        scene_file = "s.png"
    before = {name: (scene / name).read_bytes() for name in os.listdir(scene)
              if (scene / name).is_file()}
    result = rtcl(*SMALL, "-s", scene_file, *options, cwd=scene)
    expect_refused(result, 2, message)
    assert "rtcl does not replace a file the run reads" in result.stderr
    after = {name: (scene / name).read_bytes() for name in os.listdir(scene)
             if (scene / name).is_file()}
    assert after == before


def test_the_dump_binary_naming_the_scene_or_an_output_is_refused(scene):
    result = rtcl(*SMALL, "-s", "s.json", "-o", "o.png", cwd=scene,
                  env={"RTCL_DUMP_BINARY": "hard.json"})
    expect_refused(result, 2, "RTCL_DUMP_BINARY hard.json names the scene file s.json")
    result = rtcl(*SMALL, "-s", "s.json", "-o", "o.png", cwd=scene,
                  env={"RTCL_DUMP_BINARY": "./o.png"})
    expect_refused(result, 2, "-o/--output o.png and RTCL_DUMP_BINARY ./o.png name the same "
                   "file")
    assert not (scene / "o.png").exists()


def test_an_output_naming_the_scene_is_refused_under_mpi(scene):
    if shutil.which("mpirun") is None:
        pytest.skip("no mpirun")
    result = subprocess.run(["mpirun", "--oversubscribe", "-np", "2", RTCL, "--mpi", *SMALL,
                             "-s", "s.json", "-o", "o.png", "--stats", "hard.json"],
                            capture_output=True, text=True, cwd=scene, timeout=120,
                            env={**os.environ, **MPI_ENV})
    if "built without MPI" in result.stderr:
        pytest.skip("rtcl built without MPI")
    assert result.returncode == 2, result.stderr
    messages = [line for line in result.stderr.splitlines() if line.startswith("rtcl:")]
    assert messages == ["rtcl: rank 0: --stats hard.json names the scene file s.json: rtcl "
                        "does not replace a file the run reads; give the output another name"]
    assert (scene / "s.json").read_text().startswith('{"format"')
    assert not (scene / "o.png").exists()


# ---- 2. a commit replaces every target or none ------------------------------

def test_a_failed_rename_puts_back_the_outputs_already_replaced(tmp_path):
    (tmp_path / "out.png").write_bytes(PREVIOUS)
    (tmp_path / "s.json").write_bytes(PREVIOUS)
    # The second rename (the stats) fails, as over a bind-mounted file.
    result = rtcl(*SMALL, "-o", "out.png", "--stats", "s.json", "--flops", "new.npy",
                  cwd=tmp_path, env={"RTCL_TEST_FAIL_RENAME": "4"})
    expect_refused(result, 1, "s.json: cannot replace: Input/output error; no output was "
                   "replaced")
    assert (tmp_path / "out.png").read_bytes() == PREVIOUS
    assert (tmp_path / "s.json").read_bytes() == PREVIOUS
    assert listing(tmp_path) == ["out.png", "s.json"]  # new.npy and its sidecar are gone


def test_a_bind_mounted_target_replaces_nothing(tmp_path):
    (tmp_path / "out.png").write_bytes(PREVIOUS)
    (tmp_path / "mounted").write_bytes(PREVIOUS)
    (tmp_path / "s.json").write_bytes(b"")
    if shutil.which("mount") is None or subprocess.run(
            ["mount", "--bind", str(tmp_path / "mounted"), str(tmp_path / "s.json")],
            capture_output=True).returncode != 0:
        pytest.skip("cannot bind-mount a file here (needs root)")
    try:
        result = rtcl(*SMALL, "-o", "out.png", "--stats", "s.json", cwd=tmp_path)
    finally:
        subprocess.run(["umount", str(tmp_path / "s.json")])
    assert (tmp_path / "out.png").read_bytes() == PREVIOUS
    assert (tmp_path / "mounted").read_bytes() == PREVIOUS
    expect_refused(result, 1, "s.json: cannot replace: Device or resource busy; no output was "
                   "replaced")
    assert listing(tmp_path) == ["mounted", "out.png", "s.json"]


def test_a_failed_rename_leaves_every_frame_old(tmp_path):
    for f in (1, 2, 3):
        (tmp_path / f"f_000{f}.png").write_bytes(PREVIOUS)
    result = rtcl(*SMALL, "--frames", "1:3", "-o", "f.png", cwd=tmp_path,
                  env={"RTCL_TEST_FAIL_RENAME": "3"})
    expect_refused(result, 1, "f_0003.png: cannot replace")
    for f in (1, 2, 3):
        assert (tmp_path / f"f_000{f}.png").read_bytes() == PREVIOUS
    assert listing(tmp_path) == ["f_0001.png", "f_0002.png", "f_0003.png"]


def test_a_target_that_became_a_folder_during_the_render_replaces_nothing(tmp_path):
    for f in (1, 2, 3):
        (tmp_path / f"f_000{f}.png").write_bytes(PREVIOUS)
    # Each frame takes 0.8 s more; frame 2 is replaced by a folder once it
    # is staged, while frame 3 renders.
    process = subprocess.Popen([RTCL, *SMALL, "--frames", "1:3", "-o", "f.png"], cwd=tmp_path,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env={**os.environ, "RTCL_TEST_SLOW_DEVICE": "0:800"})
    wait_for(lambda: staged(tmp_path, "f_0002.png"), process)
    (tmp_path / "f_0002.png").unlink()
    (tmp_path / "f_0002.png").mkdir()
    (tmp_path / "f_0002.png" / "keep").write_bytes(b"a file in it")
    _, stderr = process.communicate(timeout=60)
    assert (tmp_path / "f_0001.png").read_bytes() == PREVIOUS
    assert (tmp_path / "f_0003.png").read_bytes() == PREVIOUS
    assert (tmp_path / "f_0002.png" / "keep").read_bytes() == b"a file in it"
    assert listing(tmp_path) == ["f_0001.png", "f_0002.png", "f_0003.png"]
    assert process.returncode == 1, stderr
    assert stderr.splitlines() == ["rtcl: f_0002.png: is no longer a regular file (now a "
                                   "directory), so it cannot be replaced; no output was "
                                   "replaced"]


def test_an_immutable_target_replaces_nothing(tmp_path):
    for name in ("f_0001.png", "f_0002.png", "s.json"):
        (tmp_path / name).write_bytes(PREVIOUS)
    stats = str(tmp_path / "s.json")
    if shutil.which("chattr") is None or subprocess.run(
            ["chattr", "+i", stats], capture_output=True).returncode != 0:
        pytest.skip("chattr +i does not work here")
    subprocess.run(["chattr", "-i", stats], check=True)
    try:
        # The check before the render would refuse it: the flag is set once
        # frame 1 is staged, while frame 2 renders (0.8 s more).
        process = subprocess.Popen([RTCL, *SMALL, "--frames", "1:2", "-o", "f.png", "--stats",
                                    "s.json"], cwd=tmp_path, stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE, text=True,
                                   env={**os.environ, "RTCL_TEST_SLOW_DEVICE": "0:800"})
        wait_for(lambda: staged(tmp_path, "f_0001.png"), process)
        subprocess.run(["chattr", "+i", stats], check=True)
        _, stderr = process.communicate(timeout=60)
    finally:
        subprocess.run(["chattr", "-i", stats])
    for name in ("f_0001.png", "f_0002.png", "s.json"):
        assert (tmp_path / name).read_bytes() == PREVIOUS, name
    assert listing(tmp_path) == ["f_0001.png", "f_0002.png", "s.json"]
    assert process.returncode == 1, stderr
    assert stderr.splitlines() == ["rtcl: s.json: cannot replace: Operation not permitted; no "
                                   "output was replaced"]


# ---- 3. the RTCL_DUMP_BINARY program is an output like the others -----------

def test_an_interrupt_leaves_the_dump_binary_target_untouched(tmp_path):
    # All or nothing (--no-partial): an interrupted animation keeps its
    # finished frames otherwise, with the other outputs (test_partial.py).
    (tmp_path / "out.png").write_bytes(PREVIOUS)
    process = subprocess.Popen([RTCL, *SMALL, "--frames", "1:2", "--no-partial", "-o", "f.png"],
                               cwd=tmp_path,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env={**os.environ, "RTCL_TEST_SLOW_DEVICE": "0:800",
                                    "RTCL_DUMP_BINARY": "out.png"})
    wait_for(lambda: staged(tmp_path, "f_0001.png"), process)  # the program was built
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 128 + signal.SIGINT, stderr
    assert stderr.endswith("rtcl: interrupted; no output written\n"), stderr
    assert (tmp_path / "out.png").read_bytes() == PREVIOUS
    assert listing(tmp_path) == ["out.png"]


def test_an_interrupted_animation_writes_its_finished_frames_with_the_other_outputs(tmp_path):
    (tmp_path / "out.png").write_bytes(PREVIOUS)
    process = subprocess.Popen([RTCL, *SMALL, "--frames", "1:3", "-o", "f.png"], cwd=tmp_path,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env={**os.environ, "RTCL_TEST_SLOW_DEVICE": "0:800",
                                    "RTCL_DUMP_BINARY": "out.png"})
    wait_for(lambda: staged(tmp_path, "f_0001.png"), process)  # frame 1 done
    process.send_signal(signal.SIGINT)  # in the device's 800 ms after it
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == 128 + signal.SIGINT, stderr
    assert stderr.endswith("rtcl: interrupted; wrote the 1 frame finished of 3\n"), stderr
    assert (tmp_path / "out.png").read_bytes() != PREVIOUS  # the program, dumped
    assert listing(tmp_path) == ["f_0001.png", "out.png"]


def test_the_dump_binary_is_written_with_the_frames(tmp_path):
    result = rtcl(*SMALL, "--frames", "1:2", "-o", "f.png", cwd=tmp_path,
                  env={"RTCL_DUMP_BINARY": "p.bin"})
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "p.bin").stat().st_size > 1000
    assert listing(tmp_path) == ["f_0001.png", "f_0002.png", "p.bin"]


# ---- 13. a killed run's staged files go with the next run -------------------

def test_the_staged_frames_of_a_killed_run_are_removed_by_the_next(tmp_path):
    process = subprocess.Popen([RTCL, *SMALL, "--frames", "1:9", "-o", "f.png"], cwd=tmp_path,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               env={**os.environ, "RTCL_TEST_SLOW_DEVICE": "0:300"})
    wait_for(lambda: staged(tmp_path, "f_0002.png"), process)
    process.kill()
    process.communicate(timeout=60)
    assert listing(tmp_path) != []  # what SIGKILL leaves: nothing can remove it then
    result = rtcl(*SMALL, "-o", "other.png", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert listing(tmp_path) == ["other.png"]


def stage_folder(folder, pid):
    host = os.uname().nodename.replace("-", "_").replace("/", "_")
    return folder / f".rtcl-stage-{host}-{pid}"


def test_the_old_file_of_a_run_killed_while_committing_is_put_back(tmp_path):
    gone = subprocess.Popen(["true"])
    gone.wait()  # its pid names a process that is gone
    # Killed between moving the old x.png aside and renaming the new one in
    # (where the file system has no hard links), and after replacing y.png.
    stage = stage_folder(tmp_path, gone.pid)
    stage.mkdir()
    (stage / "old-x.png").write_bytes(PREVIOUS)
    (stage / "new-x.png-abcdef.png").write_bytes(b"new")
    (stage / "old-y.png").write_bytes(PREVIOUS)
    (tmp_path / "y.png").write_bytes(b"new")
    result = rtcl(*SMALL, "-o", "other.png", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert listing(tmp_path) == ["other.png", "x.png", "y.png"]
    assert (tmp_path / "x.png").read_bytes() == PREVIOUS
    assert (tmp_path / "y.png").read_bytes() == b"new"


def test_a_staging_folder_of_a_live_run_is_left_alone(tmp_path):
    # A run that lives on (this test's own process), on this host.
    live = stage_folder(tmp_path, os.getpid())
    live.mkdir()
    (live / "new-x.png-abcdef.png").write_bytes(b"being written")
    result = rtcl(*SMALL, "-o", "other.png", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert (live / "new-x.png-abcdef.png").read_bytes() == b"being written"


# ---- 14. a symbolic link is written through --------------------------------

def test_an_output_that_is_a_symbolic_link_is_written_through(tmp_path):
    (tmp_path / "images").mkdir()
    (tmp_path / "images" / "real.png").write_bytes(PREVIOUS)
    (tmp_path / "link.png").symlink_to("images/real.png")
    result = rtcl(*SMALL, "-o", "link.png", "--stats", "s.json", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "link.png").is_symlink()
    assert os.readlink(tmp_path / "link.png") == "images/real.png"
    assert (tmp_path / "images" / "real.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert listing(tmp_path) == ["images", "link.png", "s.json"]
    assert listing(tmp_path / "images") == ["real.png"]


def test_a_dangling_symbolic_link_is_refused_before_rendering(tmp_path):
    (tmp_path / "link.png").symlink_to("missing.png")
    result = rtcl(*SMALL, "-o", "link.png", cwd=tmp_path)
    expect_refused(result, 1, "link.png: is a symbolic link to a file that does not exist; "
                   "rtcl writes through a link only to an existing file, as cp does")
    assert (tmp_path / "link.png").is_symlink()
    assert listing(tmp_path) == ["link.png"]
