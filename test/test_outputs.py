"""Nothing lost: what rtcl does to the files it is asked to write, and to the
files already there, when it is interrupted, when two outputs name one file,
when a format cannot be written faithfully, and when a target may not be
replaced. Every test here failed on commit 528a3d8 (before the two-phase
output commit and the signal thread) and passes since.
"""
import json
import os
import pathlib
import shutil
import signal
import subprocess
import tempfile
import time

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
SMALL = ["--size", "24x16"]


def rtcl(*args, cwd, env=None, preexec_fn=None):
    return subprocess.run([RTCL, *args], capture_output=True, text=True, cwd=cwd, timeout=300,
                          env=env, preexec_fn=preexec_fn)


def writes_png():
    """Whether this build has OpenImageIO (an OIIO=0 build writes only .ppm, .pfm and
    .png)."""
    return "no OpenImageIO" not in rtcl(*SMALL, "-o", "/nonexistent-dir/x.tif",
                                        cwd="/").stderr


needs_oiio = pytest.mark.skipif(not writes_png(), reason="a build without OpenImageIO")


def expect_refused(result, status, message):
    assert result.returncode == status, (result.returncode, result.stderr)
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert message in lines[0], lines[0]
    assert result.stdout == ""


# ---- interrupts while the outputs are written -----------------------------

# A render whose image takes a noticeable time to encode (a noisy PNG) next to
# a --stats document: two outputs, committed together.
INTERRUPTED_RUN = ["-k", "naive", "--size", "700x700", "--depth", "1", "-o", "out.png",
                   "--stats", "out.json"]
PREVIOUS_IMAGE = b"the user's previous image"
PREVIOUS_STATS = b"the user's previous stats"


def staged_files(folder):
    """The files in folder's staging folders (.rtcl-stage-HOST-PID)."""
    names = []
    for stage in os.listdir(folder):
        if stage.startswith(".rtcl-stage-"):
            try:
                names += os.listdir(os.path.join(folder, stage))
            except (FileNotFoundError, NotADirectoryError):
                pass  # removed meanwhile
    return names


def start_and_signal(tmp_path, when, signal_number):
    """Starts the run, waits for the moment `when` returns true (polling
    every millisecond), sends the signal, and returns the finished process."""
    process = subprocess.Popen([RTCL, *INTERRUPTED_RUN], cwd=tmp_path, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60
    while not when() and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.001)
    process.send_signal(signal_number)
    stdout, stderr = process.communicate(timeout=60)
    return process.returncode, stdout, stderr


@needs_oiio
@pytest.mark.slow
def test_interrupts_while_writing_leave_the_old_files_or_all_new_ones(tmp_path):
    expected = tmp_path / "expected"
    expected.mkdir()
    done = rtcl(*INTERRUPTED_RUN, cwd=expected)
    assert done.returncode == 0, done.stderr
    new_image = (expected / "out.png").read_bytes()

    work = tmp_path / "work"
    work.mkdir()
    staged = lambda: staged_files(work) != []
    # Moments after the first temporary file appears (the write has begun),
    # and moments when the image has just been replaced (the commit).
    moments = [(staged, delay) for delay in (0, 0.002, 0.01, 0.03, 0.06, 0.1, 0.2)]
    replaced = lambda: (work / "out.png").read_bytes() != PREVIOUS_IMAGE
    moments += [(replaced, 0), (replaced, 0.001)]
    outcomes = set()
    for i, (event, delay) in enumerate(moments):
        (work / "out.png").write_bytes(PREVIOUS_IMAGE)
        (work / "out.json").write_bytes(PREVIOUS_STATS)
        signal_number = (signal.SIGINT, signal.SIGTERM)[i % 2]

        def when():
            if not event():
                return False
            time.sleep(delay)
            return True

        status, stdout, stderr = start_and_signal(work, when, signal_number)
        assert sorted(os.listdir(work)) == ["out.json", "out.png"], (i, os.listdir(work))
        image, stats = (work / "out.png").read_bytes(), (work / "out.json").read_bytes()
        if image == PREVIOUS_IMAGE:
            assert stats == PREVIOUS_STATS, f"moment {i}: the image is old but the stats new"
            assert status == 128 + signal_number, (i, status, stderr)
            assert stderr.endswith("rtcl: interrupted; no output written\n"), stderr
            outcomes.add("old")
        else:
            assert image == new_image, f"moment {i}: the image is neither old nor complete"
            assert json.loads(stats)["width"] == 700, f"moment {i}: the stats are old"
            if status != 0:
                assert status == 128 + signal_number, (i, status, stderr)
                assert stderr.endswith("rtcl: interrupted; the outputs were written\n"), stderr
            outcomes.add("new")
    # The moments hit both sides of the commit.
    assert outcomes == {"old", "new"}


# ---- quit and crash signals sent by a user (issue 24, finding 18) ------------

def opencl_is_up(pid):
    """Whether the OpenCL runtime has set its signal handlers (PoCL's LLVM
    catches SIGQUIT, SIGABRT and SIGSEGV, and swallowed those sent by kill)."""
    try:
        status = pathlib.Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return True
    caught = int(next(line for line in status.splitlines()
                      if line.startswith("SigCgt:")).split()[1], 16)
    return bool(caught & (1 << (signal.SIGQUIT - 1)))


@pytest.mark.parametrize("signal_number", [signal.SIGQUIT, signal.SIGABRT, signal.SIGSEGV])
def test_quit_and_crash_signals_sent_by_a_user_end_the_run_as_an_interrupt(tmp_path,
                                                                            signal_number):
    (tmp_path / "out.png").write_bytes(PREVIOUS_IMAGE)
    # Seconds of rendering (PoCL), far more than the signal needs.
    process = subprocess.Popen([RTCL, "--size", "800x600", "--spp", "16", "-o", "out.png"],
                               cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                               text=True)
    deadline = time.monotonic() + 5
    while not opencl_is_up(process.pid) and time.monotonic() < deadline:
        time.sleep(0.005)
    process.send_signal(signal_number)
    try:
        _, stderr = process.communicate(timeout=60)
    finally:
        process.kill()
    assert process.returncode == 128 + signal_number, (process.returncode, stderr)
    name = signal.Signals(signal_number).name
    assert stderr.startswith(f"rtcl: interrupted ({name}"), stderr
    assert stderr.endswith("; no output written\n") and stderr.count("\n") == 1, stderr
    assert os.listdir(tmp_path) == ["out.png"]
    assert (tmp_path / "out.png").read_bytes() == PREVIOUS_IMAGE


# ---- two outputs, one file ------------------------------------------------

@pytest.mark.parametrize("options", [
    ["-o", "x.png", "--stats", "x.png"],
    ["-o", "x.png", "--flops", "alias.npy"],
    ["-o", "x.png", "--work-map", "x.png"],
    ["--flops", "f.npy", "--stats", "f.npy.json"],
    ["-o", "x.png", "--stats", "./x.png"],
    ["-o", "x.png", "--work-map", "link/x.png"],
    ["-o", "x.png", "--stats", "hard.png"],
])
def test_two_outputs_naming_one_file_are_refused(tmp_path, options):
    (tmp_path / "link").symlink_to(".")
    (tmp_path / "x.png").write_bytes(b"previous")
    os.link(tmp_path / "x.png", tmp_path / "hard.png")
    (tmp_path / "alias.npy").symlink_to("x.png")
    result = rtcl(*SMALL, *options, cwd=tmp_path)
    expect_refused(result, 2, "name the same file: give each output a file of its own")
    assert sorted(os.listdir(tmp_path)) == ["alias.npy", "hard.png", "link", "x.png"]
    assert (tmp_path / "x.png").read_bytes() == b"previous"


# ---- formats that cannot be written faithfully ----------------------------

@needs_oiio
@pytest.mark.parametrize("extension, writer", [
    ("j2k", "jpeg2000"), ("jp2", "jpeg2000"), ("term", "term"), ("null", "null")])
def test_formats_that_do_not_read_back_are_refused(tmp_path, extension, writer):
    result = rtcl(*SMALL, "-q", "-o", f"out.{extension}", cwd=tmp_path)
    expect_refused(result, 1, f"out.{extension}: OpenImageIO's {writer} writer does not give "
                   "a file that reads back")
    assert os.listdir(tmp_path) == []


def test_a_dot_name_has_no_extension(tmp_path):
    result = rtcl(*SMALL, "-o", ".png", cwd=tmp_path)
    expect_refused(result, 1, ".png: a name that starts with a dot has no extension")
    assert os.listdir(tmp_path) == []


# ---- what the rename will need, checked before the render -----------------

def test_a_name_too_long_for_the_sidecar_is_refused_before_rendering(tmp_path):
    name = "b" * 248 + ".npy"  # the sidecar, NAME.npy.json, is 257 characters
    result = rtcl(*SMALL, "--flops", name, cwd=tmp_path)
    expect_refused(result, 1, "the file name is 257 characters long, more than the 255")
    assert os.listdir(tmp_path) == []


def as_nobody():
    os.setgroups([])
    os.setgid(65534)
    os.setuid(65534)


needs_root = pytest.mark.skipif(os.geteuid() != 0, reason="needs root to act as two users")


@pytest.fixture
def shared_dir():
    """A directory that another user can reach (pytest's own are private)."""
    path = pathlib.Path(tempfile.mkdtemp(prefix="rtcl-test-outputs-"))
    path.chmod(0o777)
    yield path
    shutil.rmtree(path)


@needs_root
def test_a_read_only_target_is_not_replaced(shared_dir):
    shared_dir.chmod(0o1777)
    target = shared_dir / "x.png"
    target.write_bytes(b"root's read-only image")
    target.chmod(0o444)
    shared_dir.chmod(0o777)  # a world-writable directory, not sticky
    result = rtcl("-k", "reference", *SMALL, "-o", str(target), cwd=shared_dir,
                  preexec_fn=as_nobody)
    expect_refused(result, 1, "exists and you cannot write it (Permission denied); rtcl "
                   "replaces only a file you could overwrite")
    assert target.read_bytes() == b"root's read-only image"
    assert os.listdir(shared_dir) == ["x.png"]


@needs_root
def test_another_users_file_in_a_sticky_directory_is_refused_before_rendering(shared_dir):
    shared_dir.chmod(0o1777)
    target = shared_dir / "x.png"
    target.write_bytes(b"root's image")
    target.chmod(0o666)
    result = rtcl("-k", "reference", *SMALL, "-o", str(target), cwd=shared_dir,
                  preexec_fn=as_nobody)
    expect_refused(result, 1, "belongs to another user in the sticky directory")
    assert target.read_bytes() == b"root's image"
    assert os.listdir(shared_dir) == ["x.png"]


def test_a_read_only_file_of_ones_own_is_not_replaced(shared_dir):
    target = shared_dir / "x.png"
    target.write_bytes(b"mine, read-only")
    target.chmod(0o444)
    preexec = as_nobody if os.geteuid() == 0 else None
    if preexec:
        shared_dir.chmod(0o777)
        os.chown(target, 65534, 65534)
    result = rtcl("-k", "reference", *SMALL, "-o", str(target), cwd=shared_dir,
                  preexec_fn=preexec)
    expect_refused(result, 1, "exists and you cannot write it")
    assert target.read_bytes() == b"mine, read-only"


# ---- reproducible files ---------------------------------------------------

@needs_oiio
@pytest.mark.parametrize("extension", ["tif", "exr"])
def test_source_date_epoch_makes_dated_formats_reproducible(tmp_path, extension):
    env = {**os.environ, "SOURCE_DATE_EPOCH": "1700000000"}
    first = rtcl(*SMALL, "-q", "-o", f"a.{extension}", cwd=tmp_path, env=env)
    assert first.returncode == 0, first.stderr
    time.sleep(1.1)  # a date in seconds would now differ
    second = rtcl(*SMALL, "-q", "-o", f"b.{extension}", cwd=tmp_path, env=env)
    assert second.returncode == 0, second.stderr
    assert (tmp_path / f"a.{extension}").read_bytes() == (tmp_path / f"b.{extension}").read_bytes()
