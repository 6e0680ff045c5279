"""The progress line (issue 22 item 3): on a terminal it moves during a pass,
names the warm-up and the timed launches of -r and the frames of --frames;
off a terminal, or with -q, nothing is printed. Runs under a pseudo-terminal
on PoCL at sizes that take a few seconds."""
import os
import re
import subprocess
from pathlib import Path

import pytest

import terminal

ROOT = Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))

# One pass (250x250 at 64 samples is 4.0 M pixel samples, the most a pass
# takes) that lasts long enough for the line to estimate the time left, which
# it does after half a second: the paper's brute force (--accel none) makes it
# about 0.85 s on an idle 2-core machine (200x150 through the BVH, 0.34 s, left
# no estimate there once the machine was idle).
ONE_PASS = ["--size", "250x250", "--spp", "64", "--accel", "none"]


def on_terminal(*args):
    """Runs rtcl with stderr on a pseudo-terminal; returns (result, the
    lines drawn on it, each redraw after a carriage return)."""
    result, shown = terminal.on_terminal([RTCL, *args], ROOT)
    return result, [line.strip() for line in shown.decode().split("\r") if line.strip()]


def shares(lines):
    return [int(m.group(1)) for line in lines if (m := re.search(r": (\d+)% done", line))]


@pytest.mark.slow  # make test's 3 minutes (cold, 2-core VM)
def test_progress_moves_during_a_single_pass(tmp_path):
    result, lines = on_terminal(*ONE_PASS, "-o", str(tmp_path / "x.ppm"))
    assert result.returncode == 0
    assert "in 1 pass" in result.stdout
    assert all(line.startswith("rendering (dynamic)") for line in lines), lines
    between = {share for share in shares(lines) if 0 < share < 100}
    assert len(between) >= 2, lines
    assert shares(lines) == sorted(shares(lines)), "the share went back"
    assert any("s left" in line for line in lines), lines


def test_no_progress_off_a_terminal_or_with_quiet(tmp_path):
    # A render short enough to be cheap, but one that shows progress on a
    # terminal (checked first), so that its silence below means something.
    short = ["--size", "100x75", "--spp", "16"]
    shown, lines = on_terminal(*short, "-o", str(tmp_path / "w.ppm"))
    assert shown.returncode == 0 and shares(lines), lines
    result = subprocess.run([RTCL, *short, "-o", str(tmp_path / "x.ppm")], cwd=ROOT,
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0
    assert result.stderr == ""
    quiet, lines = on_terminal(*short, "-q", "-o", str(tmp_path / "y.ppm"))
    assert quiet.returncode == 0 and quiet.stdout == ""
    assert lines == []


def test_repeat_names_the_warm_up_and_the_timed_launches(tmp_path):
    result, lines = on_terminal("--size", "100x75", "--spp", "16", "-r", "2", "-k", "naive",
                                "-o", str(tmp_path / "x.ppm"))
    assert result.returncode == 0
    text = "\n".join(lines)
    assert "rendering (naive, warm-up launch: " in text, text
    assert "rendering (naive, timed launch 1 of 2: " in text, text
    assert "rendering (naive, timed launch 2 of 2: " in text, text
    assert "of 3" not in text


def test_frames_show_the_frame_and_its_share(tmp_path):
    result, lines = on_terminal("--size", "100x75", "--spp", "16", "--frames", "0:1",
                                "-o", str(tmp_path / "f.ppm"))
    assert result.returncode == 0
    text = "\n".join(lines)
    assert re.search(r"rendering \(dynamic, frame 1 of 2: \d+%\): \d+% done", text), text
    assert re.search(r"rendering \(dynamic, frame 2 of 2: \d+%\): \d+% done", text), text


# cyclic in make test (its count is the one inside a loop), the others in
# make test-long: each builds four programs.
@pytest.mark.parametrize("kernel", ["cyclic", pytest.param("serial", marks=pytest.mark.slow),
                                    pytest.param("naive", marks=pytest.mark.slow)])
def test_progress_changes_neither_image_nor_flop_counts(tmp_path, kernel):
    """With the line on, serial, naive and cyclic count their chunks done
    (RTCL_PROGRESS): the pixels and the counted flops stay the same."""
    off, on = tmp_path / f"off_{kernel}", tmp_path / f"on_{kernel}"
    args = ["-k", kernel, "--size", "40x30", "--spp", "2"]
    plain = subprocess.run([RTCL, *args, "-o", f"{off}.ppm", "--flops", f"{off}.npy"],
                           cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert plain.returncode == 0 and plain.stderr == "", plain.stderr
    result, lines = on_terminal(*args, "-v", "-o", f"{on}.ppm", "--flops", f"{on}.npy")
    assert result.returncode == 0
    assert any("-DRTCL_PROGRESS" in line for line in lines), lines
    assert Path(f"{off}.ppm").read_bytes() == Path(f"{on}.ppm").read_bytes(), kernel
    assert Path(f"{off}.npy").read_bytes() == Path(f"{on}.npy").read_bytes(), kernel
