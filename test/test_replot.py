"""Tests of tools/experiments.py --replot: Table 1 and Figure 6 redrawn from a stored
results.json, without running rtcl (a --rtcl that fails if run proves it)."""
import json
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
TOOLS = ROOT / "tools"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def stats(kernel, kernel_ms, workgroup="8x8", groups="4x4"):
    return {"device": "Fake device (NVIDIA CUDA)", "kernel": kernel, "kernel_ms": kernel_ms,
            "workgroup": workgroup, "groups": groups, "global_size": [32, 32],
            "width": 32, "height": 32, "max_depth": 5, "scene": "fake", "gflop": 1.0,
            "parallel_efficiency": 0.5, "repeat": 3}


def run(role, kernel, kernel_ms, workgroup="8x8", groups="4x4"):
    return {"role": role, "kernel": kernel, "workgroup": workgroup, "groups": groups,
            "batch": None, "command": f"./rtcl -k {kernel} -w {workgroup} --groups {groups}",
            "stats": stats(kernel, kernel_ms, workgroup, groups)}


def synthetic_results():
    """The old report's layout: each "best" row re-timed, slower than its sweep's best."""
    runs = [run("serial", "serial", 1000.0, groups="1x1"),
            run("paper", "cyclic", 9.0, groups="25x25"),
            run("sweep", "cyclic", 7.0, "8x8"), run("sweep", "cyclic", 5.5, "16x8"),
            run("sweep", "cyclic", 6.0, "16x16"),
            run("best", "cyclic", 8.25, "16x8"),        # re-timed: slower than 6.0
            run("paper", "dynamic", 4.0, groups="10x10"),
            run("sweep", "dynamic", 3.5, "8x8", "46x46"), run("sweep", "dynamic", 2.5, "32x4"),
            run("best", "dynamic", 3.75, "8x8", "46x46")]   # old choice, another geometry
    return {"meta": {"commit": "abc1234", "repeat": 10, "date": "2026-11-22 08:23 UTC"},
            "paper": {}, "runs": runs}


@pytest.fixture
def failing_rtcl(tmp_path):
    """A --rtcl that leaves a mark and fails if anything runs it."""
    fake = tmp_path / "bin" / "rtcl"
    fake.parent.mkdir()
    fake.write_text(f"#!/bin/sh\ntouch {tmp_path / 'rtcl-ran'}\nexit 7\n")
    fake.chmod(0o755)
    return fake


def replot(folder, rtcl, *options):
    return subprocess.run([sys.executable, str(TOOLS / "experiments.py"), "--rtcl", str(rtcl),
                           "--replot", str(folder), *options], capture_output=True,
                          text=True, cwd=ROOT, timeout=300)


def bounds_rows(markdown):
    """Returns the Bounds table's rows by their first cell."""
    return table_rows(markdown.split("## Bounds")[1])


def test_replot_bounds_take_the_stored_peak_or_the_one_given(tmp_path, failing_rtcl):
    folder = tmp_path / "device"
    folder.mkdir()
    results = synthetic_results()
    results["meta"]["peak"] = {"gflops": 100.0, "formula": "stored at measurement"}
    (folder / "results.json").write_text(json.dumps(results))
    assert replot(folder, failing_rtcl, "--no-plots").returncode == 0
    table = (folder / "table1.md").read_text()
    assert "FP32 peak: stored at measurement" in table
    # 1 GFLOP at 100 GFLOP/s: 10 ms; cyclic's paper row takes 9.0 ms
    assert bounds_rows(table)["cyclic"][4] == "10.000"
    assert replot(folder, failing_rtcl, "--no-plots", "--peak-gflops", "1000").returncode == 0
    table = (folder / "table1.md").read_text()
    assert "--peak-gflops 1000" in table and bounds_rows(table)["cyclic"][4] == "1.000"
    refused = replot(folder, failing_rtcl, "--peak-gflops", "0")
    assert refused.returncode == 2 and "--peak-gflops 0: expected a positive number" \
        in refused.stderr
    assert not (tmp_path / "rtcl-ran").exists()


def table_rows(markdown):
    """Returns Table 1's rows by their first cell."""
    rows = {}
    for line in markdown.split("## Bounds")[0].split("## Sweep")[0].splitlines():
        cells = [cell.strip() for cell in line.strip("|").split("|")]
        if line.startswith("|") and not line.startswith("|---"):
            rows[cells[0]] = cells
    return rows


def test_replot_takes_best_rows_from_the_sweep_and_runs_no_rtcl(tmp_path, failing_rtcl):
    folder = tmp_path / "device"
    folder.mkdir()
    (folder / "results.json").write_text(json.dumps(synthetic_results()))
    (folder / "histograms.png").write_bytes(b"old histograms")
    result = replot(folder, failing_rtcl)
    assert result.returncode == 0, result.stderr
    assert not (tmp_path / "rtcl-ran").exists()
    table = (folder / "table1.md").read_text()
    rows = table_rows(table)
    assert rows["cyclic (best of sweep)"][1:4] == ["16x8", "4x4 / 32x32", "5.50"]
    assert rows["dynamic (best of sweep)"][1:4] == ["32x4", "4x4 / 32x32", "2.50"]
    speedup = rows["Implementation"].index("speedup over serial")
    assert rows["dynamic (best of sweep)"][speedup] == "400.0"  # 1,000 ms of serial / 2.5
    assert "8.25" not in table and "3.75" not in table    # the re-timed rows are gone
    assert "regenerated on " in table and "commit abc1234, 2026-11-22 08:23 UTC" in table
    assert (folder / "speedup.png").read_bytes().startswith(PNG_SIGNATURE)
    assert (folder / "histograms.png").read_bytes() == b"old histograms"
    assert "kept histograms.png as they are" in result.stderr
    assert json.loads((folder / "results.json").read_text()) == synthetic_results()


def break_runs(results):
    del results["runs"][2]["stats"]["kernel_ms"]
    return json.dumps(results)


@pytest.mark.parametrize("content, fragment", [
    (None, "results.json: cannot read: No such file or directory"),
    ("{\"meta\": ", "results.json: not valid JSON"),
    ("[1, 2]", "results.json: expected an object with \"meta\" and \"runs\""),
    (break_runs(synthetic_results()), "results.json: runs[2]: stats lack kernel_ms"),
])
def test_replot_of_a_missing_or_malformed_results_json_writes_nothing(
        tmp_path, failing_rtcl, content, fragment):
    folder = tmp_path / "device"
    folder.mkdir()
    if content is not None:
        (folder / "results.json").write_text(content)
    before = sorted(folder.iterdir())
    result = replot(folder, failing_rtcl)
    assert result.returncode == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("experiments.py: error: ")
    assert fragment in lines[0]
    assert sorted(folder.iterdir()) == before
    assert not (tmp_path / "rtcl-ran").exists()


def test_help_mentions_replot():
    result = subprocess.run([sys.executable, str(TOOLS / "experiments.py"), "--help"],
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0 and "--replot DIR" in result.stdout
