"""Tests of tools/flops_hist.py and tools/experiments.py (and of their rtcl_tools modules).

flops_hist is tested on small synthetic .npy files (with and without sidecars),
through its functions and its command line.  experiments is tested on its pure
parts (table, slug, speedups, choice of the best geometry) with fake statistics,
plus one end-to-end run against the real ./rtcl (or $RTCL) when it supports --flops.
"""
import json
import math
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
TOOLS = ROOT / "tools"
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
sys.path.insert(0, str(TOOLS))

from rtcl_tools import experiment, flops, paper, plots, report, runner, table1  # noqa: E402

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def run_tool(name, *args, cwd=None):
    return subprocess.run([sys.executable, str(TOOLS / name), *map(str, args)],
                          capture_output=True, text=True, cwd=cwd or ROOT, timeout=600)


def write_flops(path, counts, kernel="cyclic", workgroup=(8, 8), groups=(2, 2),
                sidecar=True, **overrides):
    """Writes counts as an rtcl --flops file, with a consistent sidecar unless told."""
    counts = np.asarray(counts, dtype="<u8")
    np.save(path, counts)
    if sidecar:
        meta = {"format": "rtcl-flops", "version": 1, "kernel": kernel,
                "workgroup": list(workgroup), "groups": list(groups),
                "global_size": [counts.shape[1], counts.shape[0]],
                "total_flops": int(counts.sum()),
                "parallel_efficiency": float(counts.mean() / counts.max())}
        meta.update(overrides)
        flops.sidecar_path(path).write_text(json.dumps(meta))
    return path


def random_counts(seed, shape=(16, 16), high=1_000_000):
    return np.random.default_rng(seed).integers(1, high, shape).astype("<u8")


def assert_one_line_error(result, *fragments):
    assert result.returncode == 1, (result.returncode, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    for fragment in fragments:
        assert fragment in lines[0]


# ---- flops_hist: parallel efficiency ----------------------------------------

def test_efficiency_of_uniform_work_is_one():
    assert flops.parallel_efficiency(np.full((4, 5), 77, dtype="<u8")) == 1.0


def test_efficiency_counts_idle_work_items():
    assert flops.parallel_efficiency(np.array([0, 0, 0, 4], dtype="<u8")) == 0.25


def test_efficiency_is_mean_over_max_for_random_counts():
    for seed in range(5):
        counts = random_counts(seed, (7, 9))
        expected = counts.astype(float).mean() / counts.max()
        assert flops.parallel_efficiency(counts) == pytest.approx(expected, rel=1e-12)


def test_efficiency_does_not_overflow_large_counts():
    counts = np.full((2, 2), 2**62, dtype="<u8")  # the uint64 sum would wrap
    assert flops.parallel_efficiency(counts) == 1.0


def test_efficiency_without_work_is_undefined():
    assert math.isnan(flops.parallel_efficiency(np.zeros((3, 3), dtype="<u8")))
    with pytest.raises(ValueError):
        flops.parallel_efficiency(np.zeros((0, 3), dtype="<u8"))


def test_format_efficiency():
    assert flops.format_efficiency(0.7744) == "77.44%"
    assert flops.format_efficiency(math.nan) == "n/a"


# ---- flops_hist: loading ----------------------------------------------------

def test_load_reads_counts_and_sidecar(tmp_path):
    counts = random_counts(1)
    flops_file = flops.load_flops(write_flops(tmp_path / "c.npy", counts,
                                                   groups=(25, 25)))
    assert np.array_equal(flops_file.counts, counts)
    assert flops_file.kernel == "cyclic"
    assert "work-group 8x8, groups 25x25, 16x16 work-items" in flops_file.label()
    assert flops.sidecar_mismatches(flops_file) == []


def test_load_without_sidecar_names_the_file(tmp_path):
    flops_file = flops.load_flops(write_flops(tmp_path / "mine.npy", random_counts(2),
                                                   sidecar=False))
    assert flops_file.sidecar is None
    assert flops_file.label().startswith("mine: 16x16 work-items")


def test_sidecar_that_disagrees_is_reported(tmp_path):
    path = write_flops(tmp_path / "c.npy", [[1, 2], [3, 4]], parallel_efficiency=0.9,
                       total_flops=11, global_size=[4, 1])
    problems = flops.sidecar_mismatches(flops.load_flops(path))
    assert len(problems) == 3
    assert any("parallel_efficiency 0.9" in problem and "0.625" in problem
               for problem in problems)


WAVEFRONT_LAYOUT = ("counts[0][i]: every launch's work-items one after the other (the "
                    "primary-ray launch, then one launch per bounce)")


def test_multi_pass_counts_are_one_row_of_every_launch(tmp_path):
    # The wavefront's sidecar gives the first launch's geometry (4x4 work-items),
    # its array every launch's work-items (here 16 + 8 + 4).
    counts = np.concatenate([np.full(16, 10), np.full(8, 20), [40, 0, 0, 0]])[None, :]
    path = write_flops(tmp_path / "w.npy", counts, kernel="wavefront", workgroup=(2, 2),
                       groups=(2, 2), global_size=[4, 4], layout=WAVEFRONT_LAYOUT)
    flops_file = flops.load_flops(path)
    assert flops_file.multi_pass
    assert flops.sidecar_mismatches(flops_file) == []
    assert flops_file.efficiency == pytest.approx(counts.mean() / 40)
    label = flops_file.label()
    assert "28 work-items of all launches" in label
    assert "primary rays: work-group 2x2, groups 2x2" in label
    assert "parallel efficiency over all launches" in label


def test_multi_pass_counts_that_do_not_fit_the_layout_are_reported(tmp_path):
    two_rows = write_flops(tmp_path / "a.npy", np.ones((2, 20)), kernel="wavefront",
                           global_size=[4, 4], layout=WAVEFRONT_LAYOUT)
    too_few = write_flops(tmp_path / "b.npy", np.ones((1, 10)), kernel="wavefront",
                          global_size=[4, 4], layout=WAVEFRONT_LAYOUT)
    (problem,) = flops.sidecar_mismatches(flops.load_flops(two_rows))
    assert "2 rows" in problem
    (problem,) = flops.sidecar_mismatches(flops.load_flops(too_few))
    assert "only 10 work-items" in problem


def test_single_pass_counts_keep_their_shape_check(tmp_path):
    path = write_flops(tmp_path / "n.npy", np.ones((1, 16)), kernel="naive",
                       global_size=[4, 4])
    flops_file = flops.load_flops(path)
    assert not flops_file.multi_pass
    (problem,) = flops.sidecar_mismatches(flops_file)
    assert "global_size [4, 4] but the array is 16x1" in problem


def test_flop_unit_keeps_numbers_readable():
    assert flops.flop_unit(5) == (1.0, "FLOP")
    assert flops.flop_unit(3_000_000) == (1e6, "MFLOP")
    assert flops.flop_unit(2e10) == (1e9, "GFLOP")


# ---- flops_hist: command line ------------------------------------------------

def test_cli_writes_png_with_subplots(tmp_path):
    files = [write_flops(tmp_path / f"{kernel}.npy", random_counts(seed), kernel=kernel)
             for seed, kernel in enumerate(("naive", "cyclic", "dynamic"))]
    out = tmp_path / "fig7.png"
    result = run_tool("flops_hist.py", *files, "-o", out, "--log", "--bins", 20)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    assert out.read_bytes().startswith(PNG_SIGNATURE)
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_cli_writes_svg_overlay_naming_kernels_and_efficiency(tmp_path):
    counts = np.array([[0, 0], [0, 4]], dtype="<u8")
    files = [write_flops(tmp_path / "naive.npy", counts, kernel="naive"),
             write_flops(tmp_path / "dynamic.npy", random_counts(3), kernel="dynamic")]
    out = tmp_path / "fig7.svg"
    result = run_tool("flops_hist.py", *files, "--overlay", "-o", out, "--title", "Fig 7")
    assert result.returncode == 0, result.stderr
    svg = out.read_text()
    assert svg.lstrip().startswith("<?xml") and "<svg" in svg
    # matplotlib writes text as paths but keeps it in comments: look for the labels.
    for text in ("naive", "dynamic", "25.00%", "Fig 7"):
        assert text in svg


def test_cli_warns_when_sidecar_disagrees(tmp_path):
    path = write_flops(tmp_path / "c.npy", [[1, 2], [3, 4]], parallel_efficiency=0.5)
    result = run_tool("flops_hist.py", path, "-o", tmp_path / "h.png")
    assert result.returncode == 0
    assert "warning" in result.stderr and "parallel_efficiency 0.5" in result.stderr


@pytest.mark.parametrize("dtype", ["<f4", "<i8", ">u8", "<u4"])
def test_cli_refuses_wrong_dtype(tmp_path, dtype):
    bad = tmp_path / "bad.npy"
    np.save(bad, np.ones((4, 4), dtype=dtype))
    out = tmp_path / "h.png"
    result = run_tool("flops_hist.py", bad, "-o", out)
    assert_one_line_error(result, str(bad), "dtype")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.npy"]


def test_cli_refuses_missing_file_and_writes_nothing(tmp_path):
    good = write_flops(tmp_path / "good.npy", random_counts(4), sidecar=False)
    out = tmp_path / "h.png"
    result = run_tool("flops_hist.py", good, tmp_path / "missing.npy", "-o", out)
    assert_one_line_error(result, "missing.npy", "no such file")
    assert not out.exists()


@pytest.mark.parametrize("content", [b"not numpy at all\n", b"\x93NUMPY\x01\x00garbage"])
def test_cli_refuses_unreadable_file(tmp_path, content):
    junk = tmp_path / "junk.npy"
    junk.write_bytes(content)
    result = run_tool("flops_hist.py", junk, "-o", tmp_path / "h.png")
    assert_one_line_error(result, "junk.npy")
    assert not (tmp_path / "h.png").exists()


def test_cli_refuses_unreadable_sidecar(tmp_path):
    path = write_flops(tmp_path / "c.npy", random_counts(5), sidecar=False)
    flops.sidecar_path(path).write_text("{ not json")
    result = run_tool("flops_hist.py", path, "-o", tmp_path / "h.png")
    assert_one_line_error(result, "c.npy.json", "sidecar")
    assert not (tmp_path / "h.png").exists()


def test_cli_refuses_unknown_output_format(tmp_path):
    path = write_flops(tmp_path / "c.npy", random_counts(6))
    result = run_tool("flops_hist.py", path, "-o", tmp_path / "h.bmp")
    assert_one_line_error(result, "h.bmp")
    assert not (tmp_path / "h.bmp").exists()


def test_failed_save_keeps_previous_output(tmp_path, monkeypatch):
    out = tmp_path / "h.png"
    out.write_bytes(b"previous")
    flops_file = flops.load_flops(write_flops(tmp_path / "c.npy", random_counts(7)))

    def broken_savefig(*args, **kwargs):
        raise OSError("disk full")
    monkeypatch.setattr("matplotlib.figure.Figure.savefig", broken_savefig)
    with pytest.raises(OSError):
        plots.plot_flops_histograms([flops_file], out)
    assert out.read_bytes() == b"previous"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.npy", "c.npy.json", "h.png"]


# ---- experiments: pure parts --------------------------------------------------

def fake_stats(kernel, kernel_ms, workgroup="8x8", groups="25x25", global_size=(200, 200),
               efficiency=0.8, gflop=2.0, device="NVIDIA H100 80GB HBM3 (NVIDIA CUDA)"):
    return {"rtcl_version": "0.1.0", "device": device, "device_version": "OpenCL 3.0 CUDA",
            "driver": "550.54", "kernel": kernel, "workgroup": workgroup, "groups": groups,
            "global_size": list(global_size), "width": 2000, "height": 2000, "max_depth": 5,
            "scene": "paper60.json (built-in)", "kernel_ms": kernel_ms, "repeat": 5,
            "gflop": gflop, "gflops": gflop / kernel_ms * 1e3,
            "parallel_efficiency": efficiency}


def fake_run(role, kernel, kernel_ms, batch=None, **stats):
    workgroup = stats.get("workgroup", "8x8")
    return runner.Run(role, kernel, workgroup, stats.get("groups"),
                           f"./rtcl -k {kernel} -w {workgroup}",
                           fake_stats(kernel, kernel_ms, **stats), batch=batch)


def fake_experiment():
    return [fake_run("serial", "serial", 50_000.0, efficiency=1.0, global_size=(1, 1)),
            fake_run("reference", "reference", 10_000.0,
                     device="CPU reference (C++, GLM, double precision, one core)"),
            fake_run("paper", "naive", 500.0, workgroup="16x10", groups="125x200",
                     global_size=(2000, 2000), efficiency=0.112),
            fake_run("paper", "cyclic", 100.0, efficiency=0.7744),
            fake_run("paper", "dynamic", 125.0, groups="10x10", global_size=(80, 80),
                     efficiency=0.8536),
            fake_run("paper", "persistent", 250.0, batch=1, groups="10x10",
                     global_size=(80, 80), efficiency=0.9),
            fake_run("paper", "wavefront", 400.0, groups="250x250",
                     global_size=(2000, 2000), efficiency=0.45),
            fake_run("sweep", "cyclic", 90.0, workgroup="8x8", groups="46x46"),
            fake_run("sweep", "cyclic", 80.0, workgroup="16x8", groups="20x20"),
            fake_run("best", "cyclic", 80.0, workgroup="16x8", groups="20x20")]


def table_rows(markdown):
    """Returns {first cell: cells} of the first markdown table in markdown."""
    rows = {}
    for line in markdown.splitlines():
        if line.startswith("| ") and not line.startswith("| Implementation"):
            cells = [cell.strip() for cell in line.strip("|").split("|")]
            rows.setdefault(cells[0], cells)
        elif rows and not line.startswith("|"):
            break
    return rows


def test_speedup():
    assert table1.speedup(1000.0, 4.0) == 250.0
    assert table1.speedup(None, 4.0) is None
    assert table1.speedup(1000.0, 0.0) is None


@pytest.mark.parametrize("device, slug", [
    ("NVIDIA H100 80GB HBM3 (NVIDIA CUDA)", "nvidia-h100-80gb-hbm3"),
    ("NVIDIA H100 80GB HBM3", "nvidia-h100-80gb-hbm3"),
    ("pthread-skylake-avx512-AMD EPYC (Portable Computing Language)", "pocl-amd-epyc"),
    ("cpu-x86-64-v3-Intel(R) Xeon(R) Gold 6338 (Portable Computing Language)",
     "pocl-intel-r-xeon-r-gold-6338"),
    ("gfx90a:sramecc+:xnack- (AMD Accelerated Parallel Processing)", "gfx90a-sramecc-xnack"),
])
def test_device_slug(device, slug):
    assert report.device_slug(device) == slug


def test_select_best_is_fastest_and_breaks_ties_by_efficiency():
    slow = fake_run("sweep", "dynamic", 12.0, efficiency=0.99)
    fast_low = fake_run("sweep", "dynamic", 10.0, efficiency=0.5)
    fast_high = fake_run("sweep", "dynamic", 10.0, efficiency=0.9)
    assert experiment.select_best([slow, fast_low, fast_high]) is fast_high
    with pytest.raises(ValueError):
        experiment.select_best([])


def test_scaled_groups():
    assert runner.scaled_groups("10x10", 1.5) == "15x15"
    assert runner.scaled_groups("3x2", 2.0) == "6x4"
    assert runner.scaled_groups("1x1", 0.1) == "1x1"


def test_planned_run_count_matches_the_sweep_size():
    # serial, reference, 5 paper runs; naive and wavefront 5 shapes; cyclic, dynamic
    # and persistent 5 shapes + 2 scaled counts + the paper's count.  The best of
    # each sweep is not run again.
    sweep = paper.SWEEP_WORKGROUPS, paper.SWEEP_GROUP_SCALES
    assert experiment.planned_run_count(False, False, False, *sweep) == 7 + 2 * 5 + 3 * 8
    assert experiment.planned_run_count(False, True, True, *sweep) == 6
    assert experiment.planned_run_count(True, True, True, *sweep) == 5


def test_table1_has_our_figures_beside_the_papers():
    table = table1.render_table1(fake_experiment(), {"commit": "abc1234", "repeat": 5,
                                                          "date": "2024-01-01 00:00 UTC"})
    rows = table_rows(table)
    assert list(rows) == ["serial", "CPU reference (1 core)", "naive", "cyclic", "dynamic",
                          "persistent", "wavefront", "cyclic (best of sweep)"]
    header = [c.strip() for c in table.split("| Implementation")[1].split("\n")[0].split("|")]
    column = {name: i + 1 for i, name in enumerate(header[1:-1])}

    def cell(row, name):
        return rows[row][column[name]]
    assert cell("cyclic", "time ms (median)") == "100.00"
    assert cell("cyclic", "paper time") == "0.43 s"
    assert cell("cyclic", "speedup over serial") == "500.0"
    assert cell("cyclic", "paper speedup") == "211"
    assert cell("cyclic", "speedup over CPU reference") == "100.00"
    assert cell("cyclic", "parallel efficiency") == "77.44%"
    assert cell("cyclic", "GFLOP/s") == "20.00"
    assert cell("naive", "paper efficiency") == "11.20%"
    assert cell("naive", "groups / threads") == "125x200 / 2000x2000"
    assert cell("dynamic", "paper GFLOP/s") == "43.37"
    assert cell("serial", "paper time") == "90.56 s"
    assert cell("cyclic (best of sweep)", "paper time") == "–"
    assert cell("cyclic (best of sweep)", "speedup over serial") == "625.0"
    # Beyond the paper: our figures, no paper figures, the geometry said honestly.
    assert cell("persistent", "groups / threads") == "10x10 / 80x80, batch 1"
    assert cell("persistent", "speedup over serial") == "200.0"
    assert cell("wavefront", "groups / threads").startswith("250x250 / 2000x2000 (primary")
    assert cell("wavefront", "parallel efficiency") == "45.00%"
    for row in ("persistent", "wavefront"):
        for name in ("paper time", "paper GFLOP/s", "paper efficiency", "paper speedup"):
            assert cell(row, name) == "–"
    assert "of all launches" in table and "go beyond the paper" in table
    # SIMD efficiency: nothing counted in these runs' statistics.
    assert cell("naive", "SIMD efficiency measured") == "–"
    assert cell("naive", "SIMD efficiency modelled") == "–"
    for text in ("NVIDIA H100 80GB HBM3", "driver: 550.54", "2000x2000", "max depth 5",
                 "rtcl 0.1.0", "abc1234", "2024-01-01", "## Sweep", "## Commands",
                 "./rtcl -k dynamic -w 8x8", "2.000 GFLOP, the same for every run"):
        assert text in table


def test_simd_cells_read_measured_modelled_and_not_measurable():
    measured = {"simd_efficiency_measured": {"intersect": 0.9125, "traversal": 0.8431},
                "simd_efficiency_model": 0.898}
    assert table1.simd_cells(measured) == ("91.25% / 84.31%", "89.80%")
    pocl = {"simd_efficiency_measured": "not measurable on this device",
            "simd_efficiency_model": 0.5}
    assert table1.simd_cells(pocl) == ("n/m", "50.00%")
    assert table1.simd_cells({}) == ("–", "–")
    assert table1.used_items_cell({"work_items_used": 64, "global_size": [80, 80]}) == \
        "64 of 6,400"
    assert table1.used_items_cell({"global_size": [80, 80]}) == "–"


def test_bounds_put_each_kernel_between_full_warps_and_the_flop_peak():
    # Issue 25 item 4: at 100 % SIMD = time x SIMD efficiency (measured, both
    # phases, where the device measured it; else modelled); flop-peak bound =
    # GFLOP / peak; the two factors multiply back to the time.
    run = runner.Run("paper", "naive", "8x8", None, "./rtcl -k naive",
                     {"kernel_ms": 10.0, "gflop": 2.0,
                      "simd_efficiency_measured": {"intersect": 0.9, "traversal": 0.6,
                                                   "both": 0.625},
                      "simd_efficiency_model": 0.8})
    row = dict(zip(table1.BOUND_COLUMNS, table1.bound_row(run, 1000.0)))
    assert row["SIMD efficiency"] == "62.50% (measured)"
    assert row["at 100 % SIMD ms"] == "6.25"
    assert row["flop-peak bound ms"] == "2.000"           # 2 GFLOP at 1,000 GFLOP/s
    assert row["lost to idle lanes"] == "1.60×" and row["lost elsewhere"] == "3.1×"
    assert row["share of peak"] == "20.00%"
    run.stats["simd_efficiency_measured"] = "not measurable on this device"
    row = dict(zip(table1.BOUND_COLUMNS, table1.bound_row(run, None)))
    assert row["SIMD efficiency"] == "80.00% (modelled)" and row["at 100 % SIMD ms"] == "8.00"
    assert row["flop-peak bound ms"] == "–" and row["lost elsewhere"] == "–"
    lines = "\n".join(table1.bounds_lines([run], {"gflops": None, "formula": "unknown: X"}))
    assert "## Bounds" in lines and "FP32 peak: unknown: X" in lines


def test_the_runner_asks_for_a_schedule_map_beside_the_flops(tmp_path):
    settings = runner.Settings("./rtcl", [], 3, tmp_path)
    flops_path = tmp_path / "x.npy"
    command = runner.rtcl_command(settings, "x", "dynamic", "8x8", None, 1, None, flops_path)
    assert command[-2:] == ["--schedule-map", str(tmp_path / "x.schedule.npy")]
    wavefront = runner.rtcl_command(settings, "x", "wavefront", "8x8", None, 1, None,
                                    flops_path)
    assert "--schedule-map" not in wavefront
    plain = runner.rtcl_command(settings, "x", "dynamic", "8x8", None, 1, None, None)
    assert "--schedule-map" not in plain


def test_table1_flags_kernels_that_count_different_work():
    runs = fake_experiment()
    runs[3].stats["gflop"] = 2.5
    table = table1.render_table1(runs, {"commit": None, "repeat": 5, "date": "today"})
    assert "Total work differs" in table and "commit unknown" in table


def test_table1_without_serial_has_no_speedup_over_serial():
    runs = fake_experiment()[1:]
    table = table1.render_table1(runs, {"commit": "x", "repeat": 5, "date": "today"})
    rows = table_rows(table)
    assert "serial" not in rows
    assert rows["cyclic"][-3] == "–"        # speedup over serial
    assert rows["cyclic"][-1] == "100.00"   # speedup over the CPU reference
    bars = table1.speedup_bars(runs)
    assert bars[1] == ("cyclic", None, 100.0, 211.0)


def test_speedup_bars_compare_with_the_paper():
    bars = table1.speedup_bars(fake_experiment())
    assert [bar[0] for bar in bars] == ["naive", "cyclic", "dynamic", "persistent",
                                        "wavefront", "cyclic\n(best)"]
    assert bars[0] == ("naive", 100.0, 20.0, 52.0)
    assert bars[3] == ("persistent", 200.0, 40.0, None)   # the paper has none
    assert bars[4] == ("wavefront", 125.0, 25.0, None)
    assert bars[5][3] is None


def test_plot_speedup_writes_png(tmp_path):
    out = tmp_path / "speedup.png"
    plots.plot_speedup(table1.speedup_bars(fake_experiment()), out, "test device")
    assert out.read_bytes().startswith(PNG_SIGNATURE)


def dynamic_sweep():
    """A sweep whose fastest entry (37.8 ms) is neither the first nor the last."""
    return [fake_run("sweep", "dynamic", 41.8, workgroup="8x8", groups="46x46"),
            fake_run("sweep", "dynamic", 37.8, workgroup="16x8", groups="92x92"),
            fake_run("sweep", "dynamic", 39.0, workgroup="8x8", groups="10x10")]


def test_best_of_sweep_is_the_fastest_entry_with_its_own_time():
    sweep = dynamic_sweep()
    best = experiment.best_of_sweep(sweep)
    assert best.role == "best" and best.kernel == "dynamic"
    assert best.stats["kernel_ms"] == 37.8 == min(run.stats["kernel_ms"] for run in sweep)
    assert (best.workgroup, best.stats["groups"]) == ("16x8", "92x92")
    assert best.command == sweep[1].command and sweep[1].role == "sweep"


def test_table1_best_row_is_the_fastest_sweep_entry():
    runs = fake_experiment()[:7] + dynamic_sweep()
    runs.append(experiment.best_of_sweep(runs[7:]))
    table = table1.render_table1(runs, {"commit": "x", "repeat": 5, "date": "today"})
    best = table_rows(table)["dynamic (best of sweep)"]
    assert best[1:4] == ["16x8", "92x92 / 200x200", "37.80"]
    assert best[-3] == "1,322.8"     # 50,000 ms of serial / 37.8 ms
    assert "entry's own time (median of 3 launches), not re-timed" in table
    commands = table.split("## Commands")[1]
    assert commands.count("./rtcl -k dynamic") == 1 + 3   # paper, then the sweep's
    (bar,) = [bar for bar in table1.speedup_bars(runs) if bar[0] == "dynamic\n(best)"]
    assert bar[1] == pytest.approx(50_000.0 / 37.8)


def speedup_figure(bars):
    """Returns (figure, axes) of Figure 6 drawn on the Agg backend."""
    plt = plots.pyplot()
    figure = plt.figure()
    return figure, plots.draw_speedup(figure, bars, "test device")


def test_speedup_figure_has_a_panel_per_baseline_with_log_axes_from_1():
    bars = table1.speedup_bars(fake_experiment())
    figure, axes_list = speedup_figure(bars)
    try:
        titles = [axes.get_title() for axes in axes_list]
        assert titles == ["rtcl over one work-item on this device\n(the serial kernel)",
                          "rtcl over its CPU reference\n(C++, one core)",
                          "the paper over its CPU program\n(serial C, Lincoln, 2009)"]
        assert len({id(axes) for axes in axes_list}) == 3
        for axes in axes_list:
            assert axes.get_yscale() == "log"
            assert axes.get_ylim()[0] == 1.0
            assert not axes.get_shared_y_axes().get_siblings(axes)[1:]
        ours, _, theirs = axes_list
        tops = [patch.get_y() + patch.get_height() for patch in ours.patches]
        assert tops == pytest.approx([100.0, 500.0, 400.0, 200.0, 125.0, 625.0])
        assert [patch.get_y() for patch in ours.patches] == [1.0] * 6
        assert [tick.get_text() for tick in theirs.get_xticklabels()] == \
            ["naive", "cyclic", "dynamic"]
        tops = [patch.get_y() + patch.get_height() for patch in theirs.patches]
        assert tops == pytest.approx([52.0, 211.0, 206.0])
    finally:
        plots.pyplot().close(figure)


def test_speedup_figure_leaves_out_an_unmeasured_baseline_and_shows_slowdowns():
    bars = [("naive", None, 0.5, 52.0), ("cyclic", None, 4.0, 211.0)]
    figure, axes_list = speedup_figure(bars)
    try:
        assert [axes.get_title().split("\n")[0] for axes in axes_list] == \
            ["rtcl over its CPU reference", "the paper over its CPU program"]
        assert axes_list[0].get_ylim()[0] == 0.1      # the 0.5 bar still shows
        assert axes_list[1].get_ylim()[0] == 1.0
    finally:
        plots.pyplot().close(figure)


def test_failing_rtcl_is_reported_with_its_command_and_stderr(tmp_path):
    fake = tmp_path / "rtcl"
    fake.write_text("#!/bin/sh\necho 'rtcl: no OpenCL platform' >&2\nexit 3\n")
    fake.chmod(0o755)
    result = run_tool("experiments.py", "--rtcl", fake, "--quick", "--out", tmp_path / "out")
    assert result.returncode == 1
    assert "rtcl: no OpenCL platform" in result.stderr
    assert f"{fake} -k serial" in result.stderr
    assert not (tmp_path / "out").exists()


FAKE_RTCL = """\
import json, pathlib, sys
import numpy as np

# Every call is 1 ms slower than the one before: a re-timing of the sweep's
# fastest geometry would come out slower than every entry of the sweep.
options = [arg for arg in sys.argv[1:] if arg != "-q"]   # -q: the one flag
args = dict(zip(options[::2], options[1::2]))
counter = pathlib.Path(__file__).with_name("calls")
calls = int(counter.read_text()) + 1 if counter.exists() else 1
counter.write_text(str(calls))
kernel = args["-k"]
workgroup = args.get("-w", "8x8")
groups = args.get("--groups", "4x4")
counts = np.full((4, 4), 100, dtype="<u8")
stats = {"device": "Fake device (NVIDIA CUDA)", "kernel": kernel,
         "kernel_ms": 10.0 + calls, "workgroup": workgroup, "groups": groups,
         "global_size": [4, 4], "width": 4, "height": 4, "max_depth": 5,
         "scene": "fake", "gflop": counts.sum() / 1e9, "parallel_efficiency": 1.0}
pathlib.Path(args["--stats"]).write_text(json.dumps(stats))
if "--flops" in args:
    np.save(args["--flops"], counts)
    pathlib.Path(args["--flops"] + ".json").write_text(json.dumps(
        {"kernel": kernel, "workgroup": workgroup, "groups": groups,
         "global_size": [4, 4], "total_flops": int(counts.sum())}))
"""


def markdown_section_rows(markdown, heading):
    """Returns the rows (lists of cells) of the first table under heading."""
    rows = []
    for line in markdown.split(heading, 1)[1].splitlines()[3:]:
        if not line.startswith("|"):
            break
        rows.append([cell.strip() for cell in line.strip("|").split("|")])
    return rows


@pytest.mark.slow  # make test's 3 minutes (cold, 2-core VM)
def test_experiments_best_rows_keep_their_sweep_time_when_a_rerun_would_differ(tmp_path):
    fake = tmp_path / "bin" / "rtcl"
    fake.parent.mkdir()
    fake.write_text(f"#!{sys.executable}\n" + FAKE_RTCL)
    fake.chmod(0o755)
    result = run_tool("experiments.py", "--rtcl", fake, "--quick", "--no-reference",
                      "--out", tmp_path / "out")
    assert result.returncode == 0, result.stderr
    device_dir = tmp_path / "out"     # -o DIR: the files go into DIR itself
    table = (device_dir / "table1.md").read_text()
    rows = table_rows(table)
    sweep = markdown_section_rows(table, "## Sweep")
    for kernel in paper.PARALLEL_KERNELS:
        entries = [row for row in sweep if row[0] == kernel]
        fastest = min(entries, key=lambda row: float(row[3]))
        best = rows[f"{kernel} (best of sweep)"]
        assert best[1:4] == fastest[1:4], kernel   # work-group, groups, time
    results = json.loads((device_dir / "results.json").read_text())
    for best in (run for run in results["runs"] if run["role"] == "best"):
        sweep_runs = [run for run in results["runs"]
                      if run["role"] == "sweep" and run["kernel"] == best["kernel"]]
        assert best["stats"] == min(sweep_runs, key=lambda run: run["stats"]["kernel_ms"])[
            "stats"]
    calls = int((fake.parent / "calls").read_text())
    assert calls == len(results["runs"]) - len(paper.PARALLEL_KERNELS)  # no reruns
    assert f"[{calls}/{calls}]" in result.stderr
    assert (device_dir / "histograms_best.png").read_bytes().startswith(PNG_SIGNATURE)


# ---- experiments: end to end against the real rtcl --------------------------

def rtcl_supports_flops():
    """Returns None when ./rtcl can run the experiment, else why not."""
    if not os.access(RTCL, os.X_OK):
        return f"{RTCL} is not built"
    try:
        help_text = subprocess.run([RTCL, "--help"], capture_output=True, text=True,
                                   timeout=60).stdout
    except (OSError, subprocess.TimeoutExpired) as error:
        return f"{RTCL} --help failed: {error}"
    if "--flops" not in help_text:
        return f"{RTCL} does not support --flops yet"
    return None


@pytest.mark.slow
def test_experiments_quick_run_against_rtcl(tmp_path):
    reason = rtcl_supports_flops()
    if reason:
        pytest.skip(reason)
    result = run_tool("experiments.py", "--rtcl", RTCL, "--quick", "--no-sweep",
                      "--size", "64x64", "--repeat", "1", "--out", tmp_path)
    assert result.returncode == 0, result.stderr
    assert "[1/7] serial" in result.stderr and "[7/7] wavefront -w 8x8" in result.stderr
    assert "[6/7] persistent -w 8x8 --groups 10x10 --batch 1" in result.stderr
    device_dir = tmp_path
    assert (device_dir / "speedup.png").read_bytes().startswith(PNG_SIGNATURE)
    assert (device_dir / "histograms.png").read_bytes().startswith(PNG_SIGNATURE)
    assert not list(device_dir.glob("*.npy"))
    rows = table_rows((device_dir / "table1.md").read_text())
    assert {"serial", "CPU reference (1 core)", "naive", "cyclic", "dynamic", "persistent",
            "wavefront"} <= set(rows)
    results = json.loads((device_dir / "results.json").read_text())
    runs = {run["kernel"]: run["stats"] for run in results["runs"]}
    assert runs["cyclic"]["groups"] == "25x25" and runs["naive"]["workgroup"] == "16x10"
    assert runs["persistent"]["groups"] == "10x10" and runs["persistent"]["batch"] == 1
    assert runs["wavefront"]["workgroup"] == "8x8"
    kernels = ("serial", "naive", "cyclic", "dynamic", "persistent", "wavefront")
    totals = {runs[kernel]["gflop"] for kernel in kernels}
    assert len(totals) == 1, "every kernel must count the same total work"
    for kernel in kernels[1:]:
        assert 0.0 < runs[kernel]["parallel_efficiency"] <= 1.0
    # Table 1 keeps the paper's brute force (issue 11 item 4).
    assert {runs[kernel]["accel"] for kernel in kernels} == {"none"}
