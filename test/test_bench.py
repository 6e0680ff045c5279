"""Tests of tools/bench.py (rtcl-bench) and its rtcl_tools modules: the pure parts (plan, peaks, fits, table) with fake data,
then end-to-end runs of `bench.py --quick` against the real ./rtcl (or $RTCL) on
tiny images, where it writes (-o DIR, else a new rtcl-results/ folder), and its
refusals (one stderr line, exit 2, nothing written)."""
import csv
import os
import pathlib
import re
import subprocess
import sys
import types

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
TOOLS = ROOT / "tools"
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
sys.path.insert(0, str(TOOLS))

from rtcl_tools import bench_plan, bench_report, files, scaling  # noqa: E402
from rtcl_tools import peak as fp32_peak  # noqa: E402

H100 = "NVIDIA H100 80GB HBM3 (NVIDIA CUDA)"


def run_bench(*args, cwd=ROOT):
    return subprocess.run([sys.executable, str(TOOLS / "bench.py"), *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, timeout=600)


def needs_rtcl():
    if not os.access(RTCL, os.X_OK):
        pytest.skip(f"{RTCL} is not built")


# ---- the plan --------------------------------------------------------------------

def test_full_plan_covers_every_kernel_shape_count_and_batch():
    configs = bench_plan.plan(bench_plan.KERNELS, bench_plan.WORKGROUPS, bench_plan.GROUP_SCALES, bench_plan.BATCHES)
    shapes, counts = len(bench_plan.WORKGROUPS), 1 + len(bench_plan.GROUP_SCALES)
    by_kernel = {kernel: [c for c in configs if c.kernel == kernel] for kernel in bench_plan.KERNELS}
    # naive: every shape + the paper's 16x10; wavefront: every shape (8x8 is its
    # paper-like one); cyclic, dynamic: shapes x counts + the paper's geometry;
    # persistent: shapes x counts x batches + dynamic's paper geometry at batch 1.
    assert len(by_kernel["naive"]) == shapes + 1
    assert len(by_kernel["wavefront"]) == shapes
    assert len(by_kernel["cyclic"]) == len(by_kernel["dynamic"]) == shapes * counts + 1
    assert len(by_kernel["persistent"]) == shapes * counts * len(bench_plan.BATCHES) + 1
    assert len(configs) == sum(len(group) for group in by_kernel.values())
    papers = {c.kernel: (c.workgroup, c.groups, c.batch) for c in configs if c.paper}
    assert papers == {"naive": ("16x10", None, None), "cyclic": ("8x8", "25x25", None),
                      "dynamic": ("8x8", "10x10", None),
                      "persistent": ("8x8", "10x10", 1), "wavefront": ("8x8", None, None)}
    assert {c.batch for c in by_kernel["persistent"]} == set(bench_plan.BATCHES)
    assert {c.group_scale for c in by_kernel["cyclic"] if not c.paper} == \
        {1.0, *bench_plan.GROUP_SCALES}
    assert all(c.group_scale is None and c.batch is None
               for c in by_kernel["naive"] + by_kernel["wavefront"])


def test_paper_only_plan_and_serial():
    configs = bench_plan.plan(bench_plan.KERNELS, bench_plan.WORKGROUPS, bench_plan.GROUP_SCALES, bench_plan.BATCHES,
                         paper_only=True, serial=True)
    assert [c.kernel for c in configs] == ["serial", *bench_plan.KERNELS]
    assert all(c.paper for c in configs[1:])


def test_group_counts_scale_the_total():
    assert bench_plan.scaled_groups("46x46", 4) == "92x92"
    assert bench_plan.scaled_groups("46x46", 2) == "65x65"      # 4225 ~ 2 x 2116
    assert bench_plan.scaled_groups("46x46", 0.5) == "33x33"    # 1089 ~ 0.5 x 2116
    assert bench_plan.scaled_groups("1x1", 0.5) == "1x1"
    assert bench_plan.groups_total("25x4") == 100


# ---- the FP32 peak -------------------------------------------------------------

@pytest.mark.parametrize("name, units, expected", [
    (H100, 132, 132 * 128 * 2 * 1.98),
    ("NVIDIA H200 (NVIDIA CUDA)", 132, 132 * 128 * 2 * 1.98),
    ("NVIDIA H100 PCIe", 114, 114 * 128 * 2 * 1.755),
    ("NVIDIA A100-SXM4-40GB", 108, 108 * 64 * 2 * 1.41),
])
def test_gpu_peak_from_the_table(name, units, expected):
    peak = fp32_peak.gpu_peak(name, units)
    assert peak.gflops == pytest.approx(expected)
    assert f"{units} SMs" in peak.formula and "FMA" in peak.formula


@pytest.mark.parametrize("name", ["NVIDIA H200 NVL", "NVIDIA GeForce RTX 4090",
                                  "gfx90a:sramecc+:xnack-"])
def test_gpu_peak_unknown(name):
    assert fp32_peak.gpu_peak(name, 100) is None


def cpuinfo(flags, cores=2, siblings=2):
    return {"flags": flags, "cpu cores": str(cores), "siblings": str(siblings)}


def test_cpu_peak_from_flags_cores_and_clock():
    stats = {"compute_units": 4, "max_clock_mhz": 3000}
    # 4 hardware threads on 2 cores per 4 siblings: 2 cores.
    peak = fp32_peak.cpu_peak(stats, cpuinfo("fpu avx2 fma avx512f", cores=2, siblings=4), 2)
    assert peak.gflops == pytest.approx(2 * 16 * 2 * 2 * 3.0)
    assert "avx512f" in peak.formula and "3000 MHz" in peak.formula
    peak = fp32_peak.cpu_peak(stats, cpuinfo("fpu avx avx2 fma"), 1)
    assert peak.gflops == pytest.approx(4 * 8 * 1 * 2 * 3.0)
    assert fp32_peak.cpu_peak(stats, cpuinfo("fpu sse4_2 avx"), 1) is None   # no FMA
    assert fp32_peak.cpu_peak(stats, cpuinfo("avx2 fma"), None) is None       # units unknown


def peak_arguments(peak_gflops=None, fma_units=None):
    return types.SimpleNamespace(peak_gflops=peak_gflops, fma_units=fma_units)


def test_find_peak_says_what_it_cannot_tell_and_leaves_the_peak_unknown():
    pocl = {"device": "pthread-znver4-AMD EPYC (Portable Computing Language)",
            "compute_units": 2, "max_clock_mhz": 2600}
    unknown = fp32_peak.find_peak(pocl, peak_arguments(), cpuinfo("avx2 fma avx512f"))
    assert unknown.gflops is None
    assert unknown.formula.startswith("unknown") and "--fma-units" in unknown.formula
    assert fp32_peak.find_peak(pocl, peak_arguments(fma_units=1),
                           cpuinfo("avx2 fma avx512f")).gflops == pytest.approx(166.4)
    given = fp32_peak.find_peak(pocl, peak_arguments(peak_gflops=123.0), {})
    assert given.gflops == 123.0 and "given" in given.formula
    mystery = fp32_peak.find_peak({"device": "Mystery GPU", "compute_units": 8},
                                  peak_arguments(), {})
    assert mystery.gflops is None and "--peak-gflops" in mystery.formula
    h100 = fp32_peak.find_peak({"device": H100, "compute_units": 132}, peak_arguments(), {})
    assert h100.gflops == pytest.approx(66908.16)


# ---- fits and tables --------------------------------------------------------------

def test_linear_fit_of_a_line_is_exact():
    fit = scaling.linear_fit([1, 2, 3, 4], [5, 7, 9, 11])
    assert (fit.slope, fit.intercept) == (pytest.approx(2), pytest.approx(3))
    assert fit.r_squared == pytest.approx(1) and fit.max_relative_deviation < 1e-12
    assert fit.points == 4


def test_linear_fit_of_a_curve_says_so():
    xs = [1, 2, 3, 4, 5]
    fit = scaling.linear_fit(xs, [x * x for x in xs])
    assert 0.9 < fit.r_squared < 0.99
    assert fit.max_relative_deviation > 0.3   # x = 1: fit -1 against 1
    assert scaling.linear_fit([2, 2], [1, 3]) is None
    assert scaling.linear_fit([1], [1]) is None


def fake_config(kernel, ms, workgroup="8x8", groups="4x4", **keys):
    stats = {"device": H100, "driver": "580", "device_version": "OpenCL 3.0 CUDA",
             "kernel": kernel, "workgroup": workgroup, "groups": groups,
             "global_size": [32, 32], "width": 100, "height": 100, "max_depth": 5,
             "scene": "paper60.json (built-in)", "kernel_ms": ms, "kernel_ms_min": ms * 0.9,
             "kernel_ms_max": ms * 1.2, "repeat": 10, "kernel_ms_all": [ms] * 10,
             "gflop": 2.0, "rays": 50_000, "mrays_per_s": 50 / ms,
             "parallel_efficiency": 0.5, "compute_units": 132, "max_clock_mhz": 1980}
    return bench_plan.Config(kernel, workgroup, stats=stats, **keys)


def test_bench_md_sorts_by_kernel_then_time_and_bolds_each_best():
    configs = [fake_config("dynamic", 3.0, group_scale=1.0),
               fake_config("naive", 2.0),
               fake_config("dynamic", 1.0, groups="8x8", group_scale=4.0),
               bench_plan.Config("naive", "64x64", skipped="too big"),
               fake_config("naive", 1.5, workgroup="16x10", paper=True)]
    peak = fp32_peak.Peak(100.0, "given")
    text = bench_report.render_bench_md(configs, peak, {"commit": "v1-2-gabc", "repeat": 10,
                                                 "command": "tools/bench.py x",
                                                 "date": "2030-01-01 00:00 UTC"})
    table = text.split("## Every configuration")[1]
    rows = [[cell.strip().strip("*") for cell in line.strip("|").split("|")]
            for line in table.splitlines() if line.startswith("| ") and "kernel" not in line]
    assert [(r[0], r[4]) for r in rows] == [("naive", "1.500"), ("naive", "2.000"),
                                            ("naive", "–"), ("dynamic", "1.000"),
                                            ("dynamic", "3.000")]
    bold = [line for line in table.splitlines() if line.startswith("| **")]
    assert len(bold) == 2 and "**1.500**" in bold[0] and "**1.000**" in bold[1]
    assert "skipped: too big" in rows[2][-1] and "paper geometry" in rows[0][-1]
    assert rows[3][8] == "2,000.0" and rows[3][9] == "2,000.00"   # GFLOP/s, % of 100
    assert rows[3][12] == "5.00"                                     # rays / pixel
    for text_part in ("NVIDIA H100", "driver: 580", "OpenCL 3.0 CUDA", "100x100",
                      "max depth 5", "v1-2-gabc", "2030-01-01", "`tools/bench.py x`",
                      "FP32 peak: given", "2.000 GFLOP counted, the same"):
        assert text_part in text


def test_best_per_kernel_is_the_fastest_measured_row_with_its_own_time():
    # bench.py does not re-time its best: the summary repeats the sweep's row.
    configs = [fake_config("dynamic", 41.8, groups="46x46", group_scale=1.0),
               fake_config("dynamic", 37.8, workgroup="16x8", groups="92x92",
                           group_scale=4.0),
               fake_config("dynamic", 39.0, groups="10x10", paper=True),
               bench_plan.Config("dynamic", "64x64", skipped="too big")]
    text = bench_report.render_bench_md(configs, fp32_peak.Peak(100.0, "given"),
                                        {"commit": "x", "repeat": 10, "command": "c",
                                         "date": "today"})
    summary = text.split("## Best per kernel")[1].split("## Every configuration")[0]
    (row,) = [[cell.strip() for cell in line.strip("|").split("|")]
              for line in summary.splitlines() if line.startswith("| dynamic")]
    assert row[:3] == ["dynamic", "dynamic -w 16x8 --groups 92x92", "37.800"]
    bold = [line for line in text.split("## Every configuration")[1].splitlines()
            if line.startswith("| **")]
    assert len(bold) == 1 and "**37.800**" in bold[0] and "**92x92**" in bold[0]


# ---- end to end against rtcl ----------------------------------------------------

def read_csv(path):
    with open(path, newline="") as stream:
        return list(csv.DictReader(stream))


@pytest.mark.slow
def test_quick_bench_and_scaling_against_rtcl(tmp_path):
    needs_rtcl()
    out = tmp_path / "out"
    result = run_bench("--rtcl", RTCL, "--quick", "--size", "24x24", "--repeat", "3",
                       "--workgroups", "8x8,64x128", "--group-scales", "4", "--batches", "1,2",
                       "--peak-gflops", "50", "--out", out, "--scaling",
                       "--scaling-sizes", "16x16,24x24,32x32", "--scaling-spheres", "60,120")
    assert result.returncode == 0, result.stderr
    device_dir = out     # -o DIR: the files go into DIR itself
    assert sorted(p.name for p in device_dir.iterdir()) == \
        ["bench.csv", "bench.md", "scaling.csv", "scaling.md"]

    # One row per planned configuration: the 64x128 work-group (8192 work-items)
    # is refused by rtcl, and so every row derived from it.
    rows = read_csv(device_dir / "bench.csv")
    planned = [("naive", "8x8", "", ""), ("naive", "64x128", "", ""),
               ("naive", "16x10", "", "")]
    for kernel in ("cyclic", "dynamic"):
        planned += [(kernel, wg, scale, "") for wg in ("8x8", "64x128") for scale in ("1.0", "4.0")]
        planned.append((kernel, "8x8", "", ""))
    planned += [("persistent", wg, scale, batch) for wg in ("8x8", "64x128")
                for batch in ("1", "2") for scale in ("1.0", "4.0")]
    planned += [("persistent", "8x8", "", "1"), ("wavefront", "8x8", "", ""),
                ("wavefront", "64x128", "", "")]
    assert sorted((r["kernel"], r["workgroup"], r["group_scale"], r["batch"]) for r in rows) \
        == sorted(planned)
    for row in rows:
        if row["workgroup"] == "64x128":
            assert row["status"] == "skipped" and row["median_ms"] == ""
            assert "64x128" in row["reason"] and "\n" not in row["reason"]
            continue
        assert row["status"] == "ok", row
        median, low, high = (float(row[key]) for key in ("median_ms", "min_ms", "max_ms"))
        assert 0 < low <= median <= high
        times = sorted(map(float, row["kernel_ms_all"].split()))
        assert len(times) == int(row["repeat"]) == 3 and times[1] == pytest.approx(median)
        gflop, gflops = float(row["gflop"]), float(row["gflops"])
        assert gflops == pytest.approx(gflop / median * 1e3, rel=1e-9)
        assert float(row["peak_percent"]) == pytest.approx(100 * gflops / 50, rel=1e-9)
        assert float(row["rays_per_pixel"]) == pytest.approx(int(row["rays"]) / (24 * 24))
        assert 0 < float(row["parallel_efficiency"]) <= 1
        assert row["command"].startswith(RTCL) and "$TMP" in row["command"]
    measured = [row for row in rows if row["status"] == "ok"]
    assert len({row["gflop"] for row in measured}) == 1, "every kernel counts the same work"
    scaled = next(row for row in measured if row["kernel"] == "dynamic"
                  and row["group_scale"] == "4.0")
    default = next(row for row in measured if row["kernel"] == "dynamic"
                   and row["group_scale"] == "1.0" and row["workgroup"] == "8x8")
    assert int(scaled["groups_total"]) == 4 * int(default["groups_total"])
    assert {(row["groups"], row["batch"]) for row in measured
            if row["kernel"] == "persistent" and row["paper"] == "1"} == {("10x10", "1")}

    md = (device_dir / "bench.md").read_text()
    for text in ("pthread", "driver:", "OpenCL", "24x24", "max depth", "commit:",
                 "--peak-gflops 50", "FP32 peak: given", "## Best per kernel"):
        assert text in md
    table = md.split("## Every configuration")[1]
    bold = [line for line in table.splitlines() if line.startswith("| **")]
    assert len(bold) == 5   # the best of each kernel
    order = [line.split("|")[1].strip(" *") for line in table.splitlines()
             if line.startswith("| ") and "kernel |" not in line]
    assert order == sorted(order, key=bench_plan.KERNEL_ORDER.index)

    points = read_csv(device_dir / "scaling.csv")
    assert [(p["spheres"], p["width"]) for p in points] == \
        [(s, w) for s in ("60", "120") for w in ("16", "24", "32")]
    for point in points:
        megapixels = int(point["width"]) * int(point["height"]) / 1e6
        assert float(point["ms_per_megapixel"]) == pytest.approx(
            float(point["median_ms"]) / megapixels)
        assert float(point["ms_per_megapixel_sphere"]) == pytest.approx(
            float(point["ms_per_megapixel"]) / int(point["spheres"]))
    scaling = (device_dir / "scaling.md").read_text()
    assert "the fastest of the sweep" in scaling
    fits = re.findall(r"^\| (\S+) \| (\d+) \| \S+ ms/\S+ \| \S+ ms \| ([-0-9.]+) \| ([0-9.]+)%",
                      scaling, re.MULTILINE)
    assert len(fits) == 2 + 3   # per sphere count (3 sizes each), per size (2 counts each)
    for _, points_in_fit, r_squared, _ in fits:
        assert int(points_in_fit) in (2, 3) and float(r_squared) <= 1.0 + 1e-9
    for unit in (r"ms/\(MP·sphere\)", "ms/GFLOP"):   # every point: pixels x spheres, work
        assert re.search(rf"^\| 6 \| \S+ {unit} \| \S+ ms \| [-0-9.]+ \| [0-9.]+% \|$",
                         scaling, re.MULTILINE)


def test_scaling_alone_uses_the_given_configuration(tmp_path):
    needs_rtcl()
    result = run_bench("--rtcl", RTCL, "--quick", "--no-sweep", "--scaling",
                       "--scaling-config", "naive:16x8", "--scaling-sizes", "8x8,16x16",
                       "--scaling-spheres", "60", "--peak-gflops", "50", "--out", tmp_path)
    assert result.returncode == 0, result.stderr
    device_dir = tmp_path
    assert sorted(p.name for p in device_dir.iterdir()) == ["scaling.csv", "scaling.md"]
    assert "`naive -w 16x8` (given by --scaling-config)" in (device_dir / "scaling.md").read_text()
    assert [p["status"] for p in read_csv(device_dir / "scaling.csv")] == ["ok", "ok"]


@pytest.mark.parametrize("args, fragment", [
    (["--repeat", "5", "--peak-gflops", "1"], "at least 10 launches"),
    (["--quick", "--kernels", "naive,bogus"], "unknown kernel 'bogus'"),
    (["--quick", "--workgroups", "8x8,0x4"], "expected WxH"),
    (["--quick", "--group-scales", "2,-1"], "positive factors"),
    (["--quick", "--batches", "1,5000"], "up to 4096"),
    (["--quick", "--peak-gflops", "0"], "--peak-gflops"),
    (["--quick", "--repeat", "x"], "invalid int value"),
    (["--quick", "--frobnicate"], "unrecognized arguments"),
    (["--paper-only", "--batches", "2"], "takes no --batches"),
    (["--no-sweep"], "nothing to run"),
    (["--quick", "--scaling", "--scaling-config", "dynamic:8x8:huge"], "expected WxH"),
    (["--quick", "--update-committed"], "takes no --out"),
])
def test_bad_options_are_one_line_and_exit_2(tmp_path, args, fragment):
    result = run_bench("--rtcl", RTCL, *args, "--out", tmp_path / "out")
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("bench.py: error: "), result.stderr
    assert fragment in lines[0]
    assert not (tmp_path / "out").exists()


def test_a_device_of_unknown_peak_is_benchmarked_into_a_new_folder(tmp_path):
    """PoCL without --fma-units: its peak is unknown, the benchmark runs all the same
    (the % of peak column empty), into rtcl-results/<device>-<date-time> of the
    current folder when no -o is given."""
    needs_rtcl()
    probe = subprocess.run([RTCL, "--list-devices"], capture_output=True, text=True)
    if "Portable Computing Language" not in probe.stdout.split("\n")[0]:
        pytest.skip("the first platform is not PoCL")
    result = run_bench("--rtcl", RTCL, "-p", "0", "-d", "0", "--quick", "--size", "16x16",
                       "--kernels", "naive", "--workgroups", "8x8", "-r", "1", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "FP32 peak: unknown" in result.stderr
    (folder,) = (tmp_path / "rtcl-results").iterdir()
    assert re.fullmatch(r"pocl-.+-\d{8}-\d{6}", folder.name)
    assert sorted(p.name for p in folder.iterdir()) == ["bench.csv", "bench.md"]
    assert "FP32 peak: unknown" in (folder / "bench.md").read_text()
    rows = read_csv(folder / "bench.csv")
    assert rows and all(row["peak_percent"] == "" for row in rows)
    assert any(row["status"] == "ok" and float(row["gflops"]) > 0 for row in rows)


def test_failing_rtcl_writes_nothing(tmp_path):
    fake = tmp_path / "rtcl"
    fake.write_text("#!/bin/sh\necho 'rtcl: no OpenCL platform' >&2\nexit 1\n")
    fake.chmod(0o755)
    result = run_bench("--rtcl", fake, "--quick", "--peak-gflops", "1", "--out",
                       tmp_path / "out")
    assert result.returncode == 1
    (line,) = result.stderr.strip().splitlines()
    assert "no OpenCL platform" in line
    assert not (tmp_path / "out").exists()


def test_failed_write_leaves_no_file(tmp_path, monkeypatch):
    replaced = []
    real_replace = os.replace

    def flaky_replace(source, target):
        if replaced:
            raise OSError("disk full")
        replaced.append(target)
        real_replace(source, target)
    monkeypatch.setattr(os, "replace", flaky_replace)
    outputs = {tmp_path / "a.csv": "a\n", tmp_path / "b.md": "b\n"}
    with pytest.raises(OSError):
        files.write_all(outputs)
    assert list(tmp_path.iterdir()) == []
