"""Time to image: a plain render launches once (the warm-up only with -r N),
and -v and --stats say where the whole process's time went."""
import json
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
SMALL = ["--size", "24x16"]
BREAKDOWN = ["device_setup", "scene_and_upload", "build", "kernels", "read_back",
             "counting_run", "encode_and_write", "total", "launches"]


def stats(tmp_path, *args):
    result = subprocess.run([RTCL, *SMALL, "-o", "x.ppm", "--stats", "s.json", *args],
                            capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert result.returncode == 0, result.stderr
    return json.loads((tmp_path / "s.json").read_text()), result


@pytest.mark.parametrize("args, launches, timed", [
    ([], 1, 1), (["-r", "1"], 2, 1), (["-r", "3"], 4, 3),
    (["-k", "wavefront"], 1, 1), (["-k", "wavefront", "-r", "2"], 3, 2),
    (["-k", "serial"], 1, 1)])
def test_a_plain_render_launches_once(tmp_path, args, launches, timed):
    doc, _ = stats(tmp_path, *args)
    assert doc["time_breakdown_ms"]["launches"] == launches
    assert doc["repeat"] == timed and len(doc["kernel_ms_all"]) == timed


def test_the_breakdown_covers_the_process(tmp_path):
    doc, result = stats(tmp_path, "-v", "--flops", "f.npy")
    times = doc["time_breakdown_ms"]
    assert sorted(times) == sorted(BREAKDOWN)
    parts = [times[key] for key in BREAKDOWN if key not in ("total", "launches")]
    assert all(part >= 0 for part in parts)
    assert times["counting_run"] > 0 and times["build"] > 0 and times["kernels"] > 0
    # The parts are laps of one clock: together no more than the total.
    assert sum(parts) <= times["total"] + 1e-6
    line = [l for l in result.stderr.splitlines() if l.startswith("rtcl: time: ")]
    assert len(line) == 1
    for words in ["device set-up", "scene and upload", "build", "kernels", "(1 launch)",
                  "read-back", "counting run", "encoding and writing", "total"]:
        assert words in line[0], line[0]


def test_the_reference_reports_its_launches(tmp_path):
    doc, _ = stats(tmp_path, "-k", "reference", "-r", "2")
    assert doc["time_breakdown_ms"]["launches"] == 2
    assert doc["time_breakdown_ms"]["kernels"] > 0
