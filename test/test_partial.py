"""What an interrupted render keeps (issue 44, item 2): Ctrl-C (SIGINT) or
SIGTERM during a render of several passes stops it after the pass under way
and writes the image of the samples done, a complete file whose samples per
pixel the summary, the stats and the file's metadata say; --checkpoint writes
such an image as the render goes; --no-partial keeps the old all-or-nothing
behaviour. RTCL_TEST_PASS_SAMPLES makes the small test images render in many
short passes, as a fast device does with large ones."""
import json
import os
import pathlib
import pty
import re
import select
import signal
import subprocess
import time

import pytest

from test_png import chunks, decode

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))

# The built-in scene (point lights, a pinhole): sample k of a pixel lies where
# it lies whatever the samples per pixel, so the first K samples of a longer
# render are exactly a K-sample render.
LONG = ["--size", "64x64", "--spp", "1024"]
PASSES = {"RTCL_TEST_PASS_SAMPLES": "16"}


def start(*args, cwd, env=None, terminal=True):
    """Starts rtcl with its stderr on a pseudo-terminal (the progress line);
    returns (process, the terminal's controller)."""
    controller, side = pty.openpty() if terminal else (None, None)
    process = subprocess.Popen([RTCL, *args], cwd=cwd, stdout=subprocess.PIPE,
                               stderr=side if terminal else subprocess.PIPE, text=True,
                               env={**os.environ, **PASSES, **(env or {})})
    if terminal:
        os.close(side)
    return process, controller


def read_terminal(controller, until, timeout=120):
    """Reads what rtcl shows on the terminal until the text matches `until`
    (a function of the text so far); returns the text."""
    shown, deadline = "", time.monotonic() + timeout
    while time.monotonic() < deadline:
        ready, _, _ = select.select([controller], [], [], 0.2)
        if not ready:
            continue
        try:
            chunk = os.read(controller, 4096)
        except OSError:  # rtcl ended
            break
        if not chunk:
            break
        shown += chunk.decode(errors="replace")
        if until(shown):
            return shown
    raise AssertionError(f"rtcl never showed what was awaited: {shown[-300:]!r}")


def share_done(at_least):
    """A test for read_terminal: the progress line shows at_least % done."""
    return lambda shown: any(int(p) >= at_least for p in re.findall(r"(\d+)% done", shown))


def finish(process, controller):
    """Waits for rtcl; returns (stdout, stderr or what the terminal showed)."""
    stdout, stderr = process.communicate(timeout=120)
    if controller is not None:
        shown = b""
        try:
            while chunk := os.read(controller, 65536):
                shown += chunk
        except OSError:  # the other end is closed: all read
            pass
        os.close(controller)
        stderr = shown.decode(errors="replace").replace("\r\n", "\n")
    return stdout, stderr


def png_samples(path):
    """The samples per pixel a PNG of rtcl's says it holds (its tEXt chunk)."""
    texts = dict(body.split(b"\0", 1) for kind, body in chunks(path.read_bytes())
                 if kind == "tEXt")
    return int(texts[b"rtcl:samples_per_pixel"]), texts[b"Description"].decode()


def interrupted_early(tmp_path, *args, signal_number=signal.SIGINT):
    process, controller = start(*LONG, "-o", "out.png", "--stats", "s.json", *args,
                                cwd=tmp_path)
    read_terminal(controller, share_done(5))
    process.send_signal(signal_number)
    stdout, _ = finish(process, controller)
    return process.returncode, stdout


@pytest.mark.parametrize("signal_number", [signal.SIGINT,
                                           pytest.param(signal.SIGTERM, marks=pytest.mark.slow)])
def test_an_interrupted_render_writes_the_samples_done(tmp_path, signal_number):
    status, stdout = interrupted_early(tmp_path, signal_number=signal_number)
    assert status == 128 + signal_number, stdout
    done, description = png_samples(tmp_path / "out.png")
    # Stopped after a pass of 16 samples, before the end.
    assert 16 <= done < 1024 and done % 16 == 0, done
    assert f"{done} of 1024 samples per pixel (interrupted)" in description
    assert f"samples: {done} of 1024 per pixel (interrupted" in stdout
    stats = json.loads((tmp_path / "s.json").read_text())
    assert (stats["samples"], stats["samples_done"]) == (1024, done)
    assert sorted(os.listdir(tmp_path)) == ["out.png", "s.json"]  # nothing staged left
    # The image is exactly the render of that many samples: a complete file
    # whose every pixel holds the mean of its first `done` samples.
    subprocess.run([RTCL, "-q", "--size", "64x64", "--spp", str(done), "-o", "whole.png"],
                   cwd=tmp_path, check=True, timeout=300)
    assert decode(tmp_path / "out.png") == decode(tmp_path / "whole.png")


@pytest.mark.slow
def test_the_stop_is_said_and_a_second_interrupt_writes_nothing(tmp_path):
    # Four long passes (256 samples each): the second interrupt comes while
    # the pass under way runs, not after the image is written.
    process, controller = start(*LONG, "-o", "out.png", cwd=tmp_path,
                                env={"RTCL_TEST_PASS_SAMPLES": "256"})
    read_terminal(controller, share_done(30))  # the first pass done: the stop allowed
    process.send_signal(signal.SIGINT)
    read_terminal(controller, lambda shown: "interrupt again" in shown)
    process.send_signal(signal.SIGINT)
    _, shown = finish(process, controller)
    assert process.returncode == 128 + signal.SIGINT, shown
    assert shown.endswith("rtcl: interrupted; no output written\n"), shown
    assert os.listdir(tmp_path) == []


def test_no_partial_keeps_a_render_all_or_nothing(tmp_path):
    status, stdout = interrupted_early(tmp_path, "--no-partial")
    assert status == 128 + signal.SIGINT
    assert stdout == ""
    assert os.listdir(tmp_path) == []


def test_checkpoints_are_complete_images_of_the_samples_so_far(tmp_path):
    # 4096 samples: on a fast machine too, the first checkpoint comes long
    # before the end; the test stops the render once it has seen one.
    process, controller = start("--size", "64x64", "--spp", "4096", "-o", "out.png",
                                "--checkpoint", "1", cwd=tmp_path)
    out = tmp_path / "out.png"
    deadline = time.monotonic() + 120
    while not out.exists() and time.monotonic() < deadline and process.poll() is None:
        time.sleep(0.02)
    # A checkpoint is committed as every output is: whole, under its name.
    done, description = png_samples(out)
    assert 16 <= done < 4096 and done % 16 == 0, done
    assert f"{done} of 4096 samples per pixel (a checkpoint)" in description
    assert decode(out)[0] == (64, 64)
    process.send_signal(signal.SIGINT)
    stdout, _ = finish(process, controller)
    assert process.returncode == 128 + signal.SIGINT
    assert re.search(r"output:  \S*out.png \(\d+ checkpoints? before it\)", stdout), stdout
    later, _ = png_samples(out)
    assert done <= later < 4096
    assert sorted(os.listdir(tmp_path)) == ["out.png"]


@pytest.mark.slow
def test_the_reference_keeps_its_samples_too(tmp_path):
    process, _ = start("-k", "reference", *LONG, "-o", "out.png", cwd=tmp_path, terminal=False)
    time.sleep(1.5)  # the reference builds nothing: it renders at once
    process.send_signal(signal.SIGINT)
    stdout, _ = finish(process, None)
    assert process.returncode == 128 + signal.SIGINT, stdout
    done, _ = png_samples(tmp_path / "out.png")
    assert 1 <= done < 1024
    subprocess.run([RTCL, "-q", "-k", "reference", "--size", "64x64", "--spp", str(done), "-o",
                    "whole.png"], cwd=tmp_path, check=True, timeout=300)
    assert decode(tmp_path / "out.png") == decode(tmp_path / "whole.png")


@pytest.mark.slow
def test_the_path_reference_keeps_its_samples_too(tmp_path):
    # The path integrator's light samples depend on the samples per pixel
    # (RENDERING.md, "More dimensions"), so a K-sample render is not the
    # first K samples of a longer one; the Criterion test
    # reference_path/sample_by_sample_is_the_same_image checks the sums.
    process, _ = start("-k", "reference", "--integrator", "path", *LONG, "-o", "out.png",
                       cwd=tmp_path, terminal=False)
    time.sleep(1.5)
    process.send_signal(signal.SIGINT)
    stdout, _ = finish(process, None)
    assert process.returncode == 128 + signal.SIGINT, stdout
    done, _ = png_samples(tmp_path / "out.png")
    assert 1 <= done < 1024
    size, rgb = decode(tmp_path / "out.png")
    assert size == (64, 64) and max(rgb) > 0  # a whole image, lit
    assert sorted(os.listdir(tmp_path)) == ["out.png"]


TWO = {"POCL_DEVICES": "pthread pthread"}


@pytest.mark.slow
def test_a_sample_split_over_two_devices_adds_their_samples_done(tmp_path):
    process, controller = start(*LONG, "-o", "out.png", "--devices", "0:0,0:1", "--split",
                                "samples", cwd=tmp_path, env=TWO)
    read_terminal(controller, share_done(5))
    process.send_signal(signal.SIGINT)
    stdout, _ = finish(process, controller)
    assert process.returncode == 128 + signal.SIGINT
    done, _ = png_samples(tmp_path / "out.png")
    assert 32 <= done < 1024
    assert f"samples: {done} of 1024 per pixel" in stdout


@pytest.mark.slow
def test_pieces_of_pixels_over_two_devices_write_nothing(tmp_path):
    process, controller = start(*LONG, "-o", "out.png", "--devices", "0:0,0:1", "--split",
                                "dynamic", cwd=tmp_path, env=TWO)
    read_terminal(controller, share_done(5))
    process.send_signal(signal.SIGINT)
    finish(process, controller)
    assert process.returncode == 128 + signal.SIGINT
    assert os.listdir(tmp_path) == []


@pytest.mark.slow
def test_an_interrupted_animation_keeps_its_finished_frames(tmp_path):
    process, controller = start("--size", "32x32", "--spp", "256", "--frames", "1:4", "-o",
                                "f.png", cwd=tmp_path)
    read_terminal(controller, lambda shown: "frame 3 of 4" in shown)
    process.send_signal(signal.SIGINT)
    stdout, _ = finish(process, controller)
    assert process.returncode == 128 + signal.SIGINT
    written = sorted(os.listdir(tmp_path))
    assert written[:2] == ["f_0001.png", "f_0002.png"] and "f_0004.png" not in written
    for name in written:  # every frame written holds all its samples
        assert png_samples(tmp_path / name)[0] == 256
    assert f"the {len(written)} frame" in stdout


@pytest.mark.parametrize("args, message", [
    (["--checkpoint", "0"], "--checkpoint: expected"),
    (["--checkpoint", "5", "--frames", "1:2"], "--checkpoint writes the image of one render "
                                               "as it goes: it does not go with --frames"),
    (["--checkpoint", "5", "--no-partial"], "it does not go with --no-partial"),
    (["--checkpoint", "5", "-r", "3"], "it does not go with -r/--repeat"),
])
def test_checkpoint_refuses_what_it_does_not_go_with(tmp_path, args, message):
    result = subprocess.run([RTCL, *args, "-o", "x.png"], cwd=tmp_path, capture_output=True,
                            text=True, timeout=60)
    assert result.returncode == 2, result.stderr
    assert message in result.stderr
    assert os.listdir(tmp_path) == []


def test_checkpoint_on_several_devices_is_refused_before_any_work(tmp_path):
    result = subprocess.run([RTCL, *LONG, "--checkpoint", "5", "--devices", "0:0,0:1", "-o",
                             "x.png"], cwd=tmp_path, capture_output=True, text=True, timeout=60,
                            env={**os.environ, **TWO})
    assert result.returncode == 1, result.stderr
    assert "--checkpoint writes the image of a render on one device" in result.stderr
    assert os.listdir(tmp_path) == []


@pytest.mark.slow
@pytest.mark.parametrize("args", [["-k", "wavefront"], ["-k", "serial"], ["--queues", "3"],
                                  ["-k", "persistent", "--queues", "2"]])
def test_every_renderer_keeps_exactly_the_samples_done(tmp_path, args):
    """The wavefront's passes, one work-item's, and the launches of several
    queues (singlepass_passes, stopped between passes on every queue) alike."""
    status, _ = interrupted_early(tmp_path, *args)
    assert status == 128 + signal.SIGINT
    done, _ = png_samples(tmp_path / "out.png")
    assert 16 <= done < 1024
    subprocess.run([RTCL, "-q", "--size", "64x64", "--spp", str(done), *args, "-o",
                    "whole.png"], cwd=tmp_path, check=True, timeout=300)
    assert decode(tmp_path / "out.png") == decode(tmp_path / "whole.png")


def test_every_image_says_its_samples_per_pixel_where_the_format_has_room(tmp_path):
    for name in ("x.ppm", "x.png"):
        result = subprocess.run([RTCL, "-q", "--size", "8x6", "--spp", "3", "-o", name],
                                cwd=tmp_path, capture_output=True, text=True, timeout=300)
        assert result.returncode == 0, result.stderr
    assert b"\n# rtcl:samples_per_pixel: 3\n" in (tmp_path / "x.ppm").read_bytes()
    assert png_samples(tmp_path / "x.png")[0] == 3
    iinfo = subprocess.run(["sh", "-c", "command -v iinfo"], capture_output=True, text=True)
    if iinfo.returncode != 0 or "OIIO=0" in os.environ.get("MAKEFLAGS", ""):
        return  # OpenImageIO's tools are not installed: the EXR is not read back
    result = subprocess.run([RTCL, "-q", "--size", "8x6", "--spp", "3", "-o", "x.exr"],
                            cwd=tmp_path, capture_output=True, text=True, timeout=300)
    if "OpenImageIO" in result.stderr:
        return  # a build without it (OIIO=0)
    assert result.returncode == 0, result.stderr
    shown = subprocess.run(["iinfo", "-v", "x.exr"], cwd=tmp_path, capture_output=True,
                           text=True, timeout=60).stdout
    assert "rtcl:samples_per_pixel: 3" in shown, shown
