"""tools/time_to_image.py: the rtcl vs POV-Ray time-to-image benchmark, run
with fake rtcl and povray executables (what it runs, parses and reports; no
timing is asserted)."""
import os
import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
TOOL = ROOT / "tools" / "time_to_image.py"
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools import time_to_image as tti  # noqa: E402

TIME_LINE = ("rtcl: time: device set-up 20.5 ms, scene and upload 0.1 ms, build 3.0 ms%s, "
             "kernels 290.0 ms (1 launch), read-back 6.0 ms, counting run 0.0 ms, encoding "
             "and writing 40.0 ms; total 360.0 ms")

FAKE_RTCL = r'''#!/usr/bin/env python3
import os, sys
args = sys.argv[1:]
with open(os.environ["FAKE_LOG"], "a") as log:
    log.write("rtcl " + " ".join(args) + "\n")
if os.environ.get("FAKE_RTCL_FAIL") and "-q" in args:
    sys.exit("rtcl: scene.json: something is wrong")
open(args[args.index("-o") + 1], "wb").write(b"image")
if "-v" in args:
    print("rtcl: platform 0, device 0: Fake CL Device (Fake Platform)", file=sys.stderr)
    print(os.environ["FAKE_TIME_LINE"], file=sys.stderr)
'''

FAKE_POVRAY = r'''#!/usr/bin/env python3
import os, sys
args = sys.argv[1:]
if args == ["--version"]:
    print("POV-Ray 3.7.0.fake")
    sys.exit(0)
with open(os.environ["FAKE_LOG"], "a") as log:
    log.write("povray " + " ".join(args) + "\n")
if "sphere {" not in open("scene.pov").read():
    sys.exit("povray: scene.pov holds no sphere")
out = [a[2:] for a in args if a.startswith("+O")][0]
open(out, "wb").write(b"image")
'''


@pytest.fixture
def fakes(tmp_path):
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    for name, text in [("rtcl", FAKE_RTCL), ("povray", FAKE_POVRAY)]:
        (bin_dir / name).write_text(text)
        (bin_dir / name).chmod(0o755)
    env = dict(os.environ, FAKE_LOG=str(tmp_path / "log"), FAKE_TIME_LINE=TIME_LINE % "",
               PATH=str(bin_dir) + os.pathsep + os.environ["PATH"])
    return bin_dir, env


def run_tool(env, *args, cwd):
    return subprocess.run([sys.executable, str(TOOL), *map(str, args)], capture_output=True,
                          text=True, env=env, cwd=cwd, timeout=300)


@pytest.mark.slow  # make test's 3 minutes (cold, 2-core VM)
def test_runs_both_interleaved_and_reports(tmp_path, fakes):
    bin_dir, env = fakes
    done = run_tool(env, "--rtcl", bin_dir / "rtcl", "--runs", "3", "--size", "40x30",
                    "-o", tmp_path / "report.txt", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "report.txt").read_text() == done.stdout
    out = done.stdout
    assert "scene: tools/genscene.py --balls 60 --seed 7 --size 40x30 --depth 5" in out
    assert "rtcl device: Fake CL Device (Fake Platform)" in out
    assert "povray: POV-Ray 3.7.0.fake, +WT2" in out
    assert re.search(r"^rtcl:   median [0-9.]+ s, min [0-9.]+ s, max [0-9.]+ s \(3 runs\)$",
                     out, re.M)
    assert re.search(r"^ratio rtcl/povray \(medians\): [0-9.]+; target <= 0\.50: (met|missed)$",
                     out, re.M)
    assert re.search(r"^CPU time \(user \+ system, all threads\), median: rtcl [0-9.]+ s, "
                     r"povray [0-9.]+ s, ratio [0-9.]+$", out, re.M)
    assert ("rtcl -v breakdown (median of 3): device set-up 20.5, scene and upload 0.1, "
            "build 3.0, kernels 290.0, read-back 6.0, counting run 0.0, encoding and writing "
            "40.0, total 360.0 ms") in out
    log = (tmp_path / "log").read_text().splitlines()
    programs = [line.split()[0] for line in log]
    # The device probe, a warm-up of each, 3 rounds in alternating order, 3 -v runs.
    assert programs == ["rtcl", "rtcl", "povray", "rtcl", "povray", "povray", "rtcl", "rtcl",
                        "povray", "rtcl", "rtcl", "rtcl"]
    plain = [line for line in log if line.startswith("rtcl") and line.endswith("-q")]
    assert len(plain) == 4
    assert re.fullmatch(r"rtcl -s \S+scene\.json --size 40x30 --encoding linear "
                        r"-o render\.png -q", plain[0]), plain[0]
    pov = [line for line in log if line.startswith("povray")]
    assert pov[0] == ("povray +Iscene.pov +Orender.png +W40 +H30 -A +WT2 -D +FN "
                      "File_Gamma=1.0")


def test_a_given_scene_is_named(tmp_path, fakes):
    bin_dir, env = fakes
    done = run_tool(env, "--rtcl", bin_dir / "rtcl", "--runs", "1", "--size", "8x8", "-s",
                    ROOT / "scenes" / "two_balls.json", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "scene: %s" % (ROOT / "scenes" / "two_balls.json") in done.stdout


def test_a_cached_build_is_reported(tmp_path, fakes):
    bin_dir, env = fakes
    env["FAKE_TIME_LINE"] = TIME_LINE % " (cached)"
    done = run_tool(env, "--rtcl", bin_dir / "rtcl", "--runs", "1", "--size", "8x8",
                    cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "build 3.0 (cached), kernels" in done.stdout


def test_a_failing_rtcl_is_one_line(tmp_path, fakes):
    bin_dir, env = fakes
    env["FAKE_RTCL_FAIL"] = "1"
    done = run_tool(env, "--rtcl", bin_dir / "rtcl", "--runs", "1", "--size", "8x8",
                    "-o", tmp_path / "report.txt", cwd=tmp_path)
    assert done.returncode == 1 and done.stdout == ""
    assert done.stderr == ("time_to_image.py: rtcl failed (exit 1): rtcl: scene.json: "
                           "something is wrong\n")
    assert not (tmp_path / "report.txt").exists()


@pytest.mark.parametrize("args, message", [
    (["--povray", "no-such-povray"], "no-such-povray not found on PATH"),
    (["--rtcl", "/nonexistent/rtcl"], "/nonexistent/rtcl is not an executable"),
    (["-s", "/nonexistent/scene.json"], "No such file or directory"),
])
def test_missing_things_are_one_line(tmp_path, fakes, args, message):
    bin_dir, env = fakes
    done = run_tool(env, "--rtcl", bin_dir / "rtcl", "--runs", "1", *args, cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    assert done.stderr.count("\n") == 1 and message in done.stderr, done.stderr


@pytest.mark.parametrize("args", [["--runs", "0"], ["--threads", "0"], ["--size", "10"]])
def test_bad_options_exit_2(tmp_path, args):
    done = run_tool(dict(os.environ), *args, cwd=tmp_path)
    assert done.returncode == 2 and "error:" in done.stderr


def test_parse_breakdown():
    parts = tti.parse_breakdown("rtcl: platform 0\n" + TIME_LINE % " (cached)" + "\n")
    assert parts["build"] == 3.0 and parts["build_cached"] is True
    assert parts["total"] == 360.0 and parts["encoding and writing"] == 40.0
    assert tti.parse_breakdown(TIME_LINE % "")["build_cached"] is False


@pytest.mark.parametrize("text, message", [
    ("", "printed 0"), (TIME_LINE % "" + "\n" + TIME_LINE % "", "printed 2"),
    (TIME_LINE.replace("read-back", "readback") % "", "lacks read-back"),
])
def test_parse_breakdown_refuses_what_it_cannot_read(text, message):
    with pytest.raises(tti.RunError, match=message):
        tti.parse_breakdown(text)


def test_interleaved_alternates_the_order():
    calls = []
    jobs = [("a", lambda: calls.append("a") or 1), ("b", lambda: calls.append("b") or 2)]
    assert tti.interleaved(jobs, 4) == {"a": [1, 1, 1, 1], "b": [2, 2, 2, 2]}
    assert calls == list("abbaabba")


def test_median_breakdown_and_verdict():
    one = tti.parse_breakdown(TIME_LINE % " (cached)")
    two = dict(one, kernels=100.0, build_cached=False)
    three = dict(one, kernels=500.0)
    assert tti.median_breakdown([one, two, three])["kernels"] == 290.0
    assert tti.median_breakdown([one, two, three])["build_cached"] is False
    assert tti.ratio_verdict(0.5, 1.0, 0.5) == (0.5, "met")
    assert tti.ratio_verdict(0.6, 1.0, 0.5)[1] == "missed"
