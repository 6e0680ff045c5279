"""tools/path_study.py (rtcl-path-study, issue 41): the schedules-on-paths
tables and the path-length figure from a batch's --stats files: end to end on
PoCL-made files, the GPU bounds on made-up files whose answers are known, and
its refusals."""
import json
import os
import pathlib
import re
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
TOOL = ROOT / "tools" / "path_study.py"
BOX = ROOT / "test" / "scenes" / "path_box.json"


def study(*args):
    return subprocess.run([sys.executable, str(TOOL), *map(str, args)], capture_output=True,
                          text=True, timeout=300)


def table_rows(text, first_cell):
    """The cells of the markdown rows whose first cell is first_cell."""
    return [[cell.strip() for cell in line.strip("|").split("|")]
            for line in text.splitlines() if line.startswith(f"| {first_cell} |")]


@pytest.mark.slow  # make test's 3 minutes
def test_a_pocl_batch_gives_the_tables_and_the_figure(tmp_path):
    batch = tmp_path / "batch"
    batch.mkdir()
    for round_ in (1, 2):
        for kernel in ("naive", "wavefront"):
            counting = ["--flops", tmp_path / "f.npy"] if round_ == 1 else []
            done = subprocess.run([RTCL, BOX, "-k", kernel, "--size", "16x8", "--spp", "2",
                                   "-r", "2", "-q", "-o", tmp_path / "x.pfm", *counting,
                                   "--stats", batch / f"box__{kernel}__r{round_}.json"],
                                  capture_output=True, text=True, timeout=300)
            assert done.returncode == 0, done.stderr
    done = study(batch, "-o", tmp_path / "out")
    assert done.returncode == 0, done.stderr
    text = (tmp_path / "out" / "paths.md").read_text()
    numbers = json.loads((tmp_path / "out" / "paths.json").read_text())
    assert (tmp_path / "out" / "path_lengths.png").read_bytes().startswith(b"\x89PNG")
    stats = {k: [json.loads((batch / f"box__{k}__r{r}.json").read_text()) for r in (1, 2)]
             for k in ("naive", "wavefront")}
    for kernel, (first, second) in stats.items():
        ms = (first["kernel_ms"] + second["kernel_ms"]) / 2      # the median of two
        row = table_rows(text, kernel)[0]
        assert row[1] == f"{ms:,.2f}"
        assert row[3] == f"{16 * 8 * 2 / ms / 1e3:,.1f}"
        assert row[5] == "does not apply (CPU)"                   # PoCL: no warps
        assert next(r for r in numbers["scenes"]["box"]
                    if r["schedule"] == kernel)["paths"] == first["paths"]
    # The paths per bounce, once, from the counting runs that agree.
    paths = stats["naive"][0]["paths"]
    assert "the same in wavefront" in text
    for b, live in enumerate(paths["live_per_bounce"]):
        assert table_rows(text, str(b))[0][1] == f"{live:,}"
    assert f"{paths['count']:,} paths, {paths['mean_length']:.3f} segments" in text


def made_up(folder, scene, schedule, round_, ms, simd=None, gflop=None, width=64, height=32,
            spp=4, paths=None):
    stats = {"device": "NVIDIA H100 80GB HBM3", "compute_units": 132, "kernel": schedule,
             "kernel_ms": ms, "width": width, "height": height, "samples": spp,
             "samples_done": spp}
    if gflop is not None:
        stats.update(gflop=gflop, total_flops=int(gflop * 1e9),
                     simd_efficiency_measured=simd, paths=paths)
    (folder / f"{scene}__{schedule}__r{round_}.json").write_text(json.dumps(stats))


def test_the_gpu_bounds_are_the_whitted_studys_with_all_three_phases(tmp_path):
    simd = {"intersect": 0.8, "traversal": 0.6, "both": 0.65, "shade": 0.4, "all": 0.5}
    paths = {"count": 10, "segments": 25, "mean_length": 2.5, "max_length": 3,
             "length_histogram": [2, 1, 7] + [0] * 13, "length_bins": 16,
             "live_per_bounce": [10, 8, 7]}
    made_up(tmp_path, "s", "naive", 1, 100.0, simd, 66.90816, paths=paths)
    made_up(tmp_path, "s", "naive", 2, 102.0)
    made_up(tmp_path, "s", "wavefront-stages", 1, 50.0, dict(simd, all=0.9), 66.90816,
            paths=paths)
    (tmp_path / "mitsuba.jsonl").write_text(
        json.dumps({"scene": "s", "form": "megakernel", "ms": 80.0, "width": 64, "height": 32,
                    "spp": 4}) + "\n" + json.dumps({"scene": "s", "form": "wavefront",
                                                    "ms": 60.0, "width": 64, "height": 32,
                                                    "spp": 4}) + "\n")
    done = study(tmp_path)
    assert done.returncode == 0, done.stderr
    text = (tmp_path / "paths.md").read_text()
    # The H100's peak from peak.py: 132 SMs x 128 lanes x 2 x 1.98 GHz = 66,908.16
    # GFLOP/s, so 66.90816 GFLOP take 1 ms at the peak.
    naive = table_rows(text, "naive")[0]
    assert naive[1:] == ["101.00", "100.00–102.00", f"{64 * 32 * 4 / 101 / 1e3:,.1f}", "1.00×",
                         "50.00% (measured, all three phases)", "50.50", "1.000", "2.00×",
                         "50.5×"]
    stages = table_rows(text, "wavefront-stages")[0]
    assert stages[4] == "2.02×" and stages[6] == "45.00" and stages[8] == "1.11×"
    assert table_rows(text, "Mitsuba 3 wavefront")[0][1] == "60.00"
    assert "Fastest schedule: **wavefront-stages**" in text
    assert "rtcl's fastest / Mitsuba's fastest: **1.20×**" in text
    phases = table_rows(text, "naive")[1]                      # the per-phase table
    assert phases[1:] == ["80.00%", "60.00%", "40.00%", "50.00%"]


def test_a_counting_run_made_apart_gives_counts_not_times(tmp_path):
    """SCENE__SCHEDULE__counted.json (run.sh's COUNT_ONLY=1): its SIMD
    efficiency and flops make the schedule's bounds, its time is not used,
    and a schedule counted but never timed has no row."""
    simd = {"intersect": 0.8, "traversal": 0.6, "both": 0.65, "shade": 0.4, "all": 0.25}
    made_up(tmp_path, "s", "naive", 1, 1.0, simd, 66.90816)
    (tmp_path / "s__naive__r1.json").rename(tmp_path / "s__naive__counted.json")
    made_up(tmp_path, "s", "naive", 1, 100.0)
    made_up(tmp_path, "s", "dynamic", 1, 5.0, simd, 66.90816)
    (tmp_path / "s__dynamic__r1.json").rename(tmp_path / "s__dynamic__counted.json")
    done = study(tmp_path)
    assert done.returncode == 0, done.stderr
    text = (tmp_path / "paths.md").read_text()
    naive = table_rows(text, "naive")[0]
    assert naive[1] == "100.00" and naive[5] == "25.00% (measured, all three phases)"
    assert naive[6] == "25.00" and naive[8] == "4.00×"
    assert not table_rows(text, "dynamic")


def test_an_approximate_mitsuba_row_says_so(tmp_path):
    made_up(tmp_path, "s", "naive", 1, 10.0)
    (tmp_path / "mitsuba.jsonl").write_text(json.dumps(
        {"scene": "s", "form": "megakernel", "ms": 20.0, "width": 64, "height": 32, "spp": 4,
         "approximate": "Mitsuba's principled (metallic 0) for the gltf plastic lobe"}) + "\n")
    done = study(tmp_path)
    assert done.returncode == 0, done.stderr
    text = (tmp_path / "paths.md").read_text()
    assert table_rows(text, "Mitsuba 3 megakernel (approximate BSDF)")
    assert "Mitsuba's exact mapping failed on this GPU: Mitsuba's principled" in text


def test_a_mitsuba_row_of_an_approximated_scene_says_what_was_approximated(tmp_path):
    made_up(tmp_path, "s", "naive", 1, 10.0)
    (tmp_path / "mitsuba.jsonl").write_text(json.dumps(
        {"scene": "s", "form": "wavefront", "ms": 20.0, "width": 64, "height": 32, "spp": 4,
         "approximate": "the mapping's approximations: plane as a 1000-unit square",
         "approximate_label": "approximate: plane as a 1000-unit square"}) + "\n")
    done = study(tmp_path)
    assert done.returncode == 0, done.stderr
    text = (tmp_path / "paths.md").read_text()
    assert table_rows(text, "Mitsuba 3 wavefront (approximate: plane as a 1000-unit square)")
    assert "Mitsuba renders a scene like this one, not the same: the mapping's" in text
    assert "exact mapping failed" not in text


@pytest.mark.parametrize("make, message", [
    (lambda folder: None, "no --stats files named SCENE__SCHEDULE__rN.json"),
    (lambda folder: (folder / "s__naive__r1.json").write_text("{"), "not a --stats file"),
    (lambda folder: (made_up(folder, "s", "naive", 1, 1.0),
                     made_up(folder, "s", "dynamic", 1, 1.0, width=32)),
     "s: the runs disagree on the image size or samples"),
])
def test_bad_input_is_one_line_and_nothing_written(tmp_path, make, message):
    make(tmp_path)
    done = study(tmp_path, "-o", tmp_path / "out")
    assert done.returncode == 1
    assert re.fullmatch(r"rtcl-path-study: .*\n", done.stderr) or \
        re.fullmatch(r"path_study.py: .*\n", done.stderr), done.stderr
    assert message in done.stderr
    assert not (tmp_path / "out").exists()
