"""Tests of tools/experiments.py as issue 11 item 8's study: --accel none|bvh and
--scene name the results folder; results.json records the accel, scene, size and
depth and keeps each run's Figure 7 histogram, so that --replot redraws every figure
from it alone; without matplotlib (or with --no-plots) results.json and table1.md
are still written.

Pure parts run on synthetic data, the command line against a fake rtcl (fast), and
one `--quick --accel bvh` run of the real ./rtcl (or $RTCL) under PoCL, shared by
the tests that read its output (a module-scoped fixture).
"""
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
TOOLS = ROOT / "tools"
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
sys.path.insert(0, str(TOOLS))

from rtcl_tools import experiment, flops, histogram, plots, report, runner, table1  # noqa: E402

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
FIGURES = ("speedup.png", "histograms.png", "histograms_best.png")
POCL = "pthread-skylake-avx512-AMD EPYC (Portable Computing Language)"


def run_tool(*args, env=None, cwd=None):
    return subprocess.run([sys.executable, str(TOOLS / "experiments.py"), *map(str, args)],
                          capture_output=True, text=True, cwd=cwd or ROOT, env=env,
                          timeout=900)


def without_matplotlib(tmp_path):
    """Returns an environment in which `import matplotlib` raises ImportError."""
    blocker = tmp_path / "blocker" / "matplotlib"
    blocker.mkdir(parents=True)
    (blocker / "__init__.py").write_text("raise ImportError('matplotlib is blocked')\n")
    return dict(os.environ, PYTHONPATH=str(blocker.parent))


@pytest.fixture
def failing_rtcl(tmp_path):
    """A --rtcl that leaves a mark and fails if anything runs it (--replot must not)."""
    fake = tmp_path / "bin" / "rtcl-must-not-run"
    fake.parent.mkdir(exist_ok=True)
    fake.write_text(f"#!/bin/sh\ntouch {tmp_path / 'rtcl-ran'}\nexit 7\n")
    fake.chmod(0o755)
    return fake


# ---- folder names and the table's header ------------------------------------------------

@pytest.mark.parametrize("accel, scene, folder", [
    ("none", None, "pocl-amd-epyc"),                      # the paper's study: as before
    ("bvh", None, "pocl-amd-epyc-bvh-paper60"),
    ("bvh", "/tmp/lake/lake-10.json", "pocl-amd-epyc-bvh-lake-10"),
    ("bvh-compact", "/tmp/lake/lake-10.json", "pocl-amd-epyc-bvh-compact-lake-10"),
    ("none", "scenes/my scene.json", "pocl-amd-epyc-none-my-scene"),
])
def test_results_folder_names_accel_and_scene(accel, scene, folder):
    out = pathlib.Path("docs/results")
    assert experiment.results_folder(out, POCL, accel, scene) == out / folder


@pytest.mark.parametrize("scene, stem", [
    (None, "paper60"), ("paper60.json (built-in)", "paper60"),
    ("/data/lake-10.json", "lake-10"), ("a/b/Wuson (glass).json", "Wuson-glass"),
])
def test_scene_stem(scene, stem):
    assert report.scene_stem(scene) == stem


def fake_stats(kernel, kernel_ms, **extra):
    stats = {"device": "Fake GPU (NVIDIA CUDA)", "kernel": kernel, "kernel_ms": kernel_ms,
             "workgroup": "8x8", "groups": "4x4", "global_size": [32, 32], "width": 400,
             "height": 300, "max_depth": 7, "scene": "paper60.json (built-in)",
             "gflop": 1.0, "parallel_efficiency": 0.5}
    return dict(stats, **extra)


def fake_runs(**extra):
    return [runner.Run("serial", "serial", None, None, "./rtcl -k serial",
                       fake_stats("serial", 100.0, **extra)),
            runner.Run("paper", "cyclic", "8x8", "25x25", "./rtcl -k cyclic",
                       fake_stats("cyclic", 2.0, **extra))]


def heading_and_accel(markdown):
    lines = markdown.splitlines()
    return lines[0], next(line for line in lines if line.startswith("- acceleration:"))


def test_table1_states_accel_scene_size_and_depth():
    meta = {"commit": "abc", "repeat": 5, "date": "today", "accel": "bvh",
            "scene": "/data/lake-10.json", "scene_stem": "lake-10", "size": "400x300",
            "depth": 7}
    runs = fake_runs(scene="/data/lake-10.json", accel="bvh")
    heading, accel = heading_and_accel(table1.render_table1(runs, meta))
    assert heading.endswith("rtcl on Fake GPU (NVIDIA CUDA), --accel bvh, scene lake-10")
    assert accel.startswith("- acceleration: `--accel bvh`: rays traverse a BVH")
    assert "CPU reference" not in accel      # no reference run in these
    assert "- scene: /data/lake-10.json, 400x300, max depth 7" in \
        table1.render_table1(runs, meta)


def test_table1_of_a_results_json_without_accel_says_brute_force():
    """results.json files made before --accel: no meta accel, no stats accel."""
    meta = {"commit": "abc", "repeat": 5, "date": "today"}
    heading, accel = heading_and_accel(table1.render_table1(fake_runs(), meta))
    assert heading == "# Table 1 reproduced: rtcl on Fake GPU (NVIDIA CUDA)"
    assert accel.startswith("- acceleration: `--accel none`: every ray tests every")


# ---- the histogram results.json keeps ----------------------------------------------------

def flops_file(tmp_path, counts, kernel="dynamic"):
    path = tmp_path / f"{kernel}.npy"
    np.save(path, np.asarray(counts, dtype="<u8"))
    flops.sidecar_path(path).write_text(json.dumps(
        {"kernel": kernel, "workgroup": [8, 8], "groups": [10, 10]}))
    return flops.load_flops(path)


@pytest.mark.parametrize("high", [5, 70_000, 3_000_000_000])   # FLOP, kFLOP, GFLOP
def test_histogram_is_what_the_figure_draws_of_the_counts(tmp_path, high):
    counts = np.random.default_rng(high).integers(0, high, (24, 40))
    counts[0, 0] = high        # the largest count is the last edge
    stored = histogram.histogram_of(flops_file(tmp_path, counts))
    assert sum(stored.counts) == stored.work_items == counts.size
    assert len(stored.edges) == len(stored.counts) + 1 == histogram.DEFAULT_BINS + 1
    assert (stored.mean, stored.max, stored.min) == (counts.mean(), high, counts.min())
    divisor, unit = flops.flop_unit(high)
    assert stored.unit == unit and stored.edges[-1] == pytest.approx(high / divisor)
    # The bars Figure 7 drew from the per-work-item values, before results.json kept
    # histograms, are the bars it now draws from the stored histogram.
    plt = plots.pyplot()
    figure = plt.figure()
    try:
        from_values = figure.add_subplot(1, 2, 1)
        from_values.hist(counts.ravel() / divisor, bins=stored.edges)
        drawn = figure.add_subplot(1, 2, 2)
        plots._draw_one(drawn, stored, divisor, unit, share=False)
        heights = [patch.get_height() for patch in drawn.patches]
        assert heights == [patch.get_height() for patch in from_values.patches]
        assert heights == stored.counts
    finally:
        plt.close(figure)


def test_histograms_of_several_kernels_share_one_unit_and_show_shares(tmp_path):
    # Figures people can read (issue 25 item 6): one flop unit per figure, the
    # one that shows the smallest subplot's largest count as 1..999, and with
    # several kernels each bar a % of its kernel's work-items.
    small = histogram.histogram_of(flops_file(tmp_path, [[0, 2_000, 4_000, 4_000]]))
    large = histogram.histogram_of(flops_file(tmp_path, [[0] * 99 + [3_000_000]],
                                              kernel="persistent"))
    plt = plots.pyplot()
    figure = plt.figure()
    try:
        plots.draw_histograms(figure, [small, large])
        axes = figure.axes
        assert [a.get_xlabel() for a in axes] == ["flops per work-item (kFLOP)"] * 2
        assert [a.get_ylabel() for a in axes] == ["% of work-items"] * 2
        for a in axes:
            assert sum(patch.get_height() for patch in a.patches) == pytest.approx(100)
        assert axes[1].patches[-1].get_x() + axes[1].patches[-1].get_width() \
            == pytest.approx(3_000)
        one = plt.figure()
        plots.draw_histograms(one, [small])          # one kernel: its counts
        assert one.axes[0].get_ylabel() == "work-items"
        assert sum(patch.get_height() for patch in one.axes[0].patches) == 4
        plt.close(one)
    finally:
        plt.close(figure)
    assert plots.tick_label(1_250_000.0) == "1,250,000" and plots.tick_label(0.5) == "0.5"


def test_histogram_survives_json_and_refuses_malformed_data(tmp_path):
    stored = histogram.histogram_of(flops_file(tmp_path, [[1, 2, 3], [4, 5, 600]]))
    item = json.loads(json.dumps(stored.to_json()))
    assert histogram.histogram_from_json(item, "here") == stored
    for key, value in (("counts", [1, 2]), ("bin_edges", [3.0, 2.0] + item["bin_edges"][2:]),
                       ("unit", "TFLOP"), ("work_items", 7), ("label", None)):
        with pytest.raises(ValueError, match="^here: "):
            histogram.histogram_from_json(dict(item, **{key: value}), "here")


def test_compact_number_lists_changes_layout_only():
    data = {"a": [1, 2.5, -3e-07], "b": {"c": [], "d": ["[1,2]", 3]}, "e": "[\n1]"}
    text = experiment.compact_number_lists(json.dumps(data, indent=2))
    assert json.loads(text) == data
    assert '"a": [1, 2.5, -3e-07]' in text


# ---- the command line against a fake rtcl ------------------------------------------------

FAKE_RTCL = """\
import json, pathlib, sys
import numpy as np

options = [arg for arg in sys.argv[1:] if arg != "-q"]   # -q: the one flag
args = dict(zip(options[::2], options[1::2]))
with open(pathlib.Path(__file__).with_name("calls"), "a") as log:
    log.write(" ".join(sys.argv[1:]) + "\\n")
counts = np.arange(1, 17, dtype="<u8").reshape(4, 4) * 100
stats = {"device": "Fake GPU (NVIDIA CUDA)", "kernel": args["-k"], "kernel_ms": 10.0,
         "workgroup": args.get("-w", "8x8"), "groups": args.get("--groups", "4x4"),
         "global_size": [4, 4], "width": 4, "height": 4, "max_depth": 5,
         "scene": args.get("-s", "paper60.json (built-in)"), "accel": args["--accel"],
         "gflop": counts.sum() / 1e9, "parallel_efficiency": 0.5}
pathlib.Path(args["--stats"]).write_text(json.dumps(stats))
if "--flops" in args:
    np.save(args["--flops"], counts)
"""


@pytest.fixture
def fake_rtcl(tmp_path):
    fake = tmp_path / "bin" / "rtcl"
    fake.parent.mkdir(exist_ok=True)
    fake.write_text(f"#!{sys.executable}\n" + FAKE_RTCL)
    fake.chmod(0o755)
    return fake


@pytest.mark.slow  # make test's 3 minutes (cold, 2-core VM)
def test_accel_and_scene_reach_every_rtcl_call_and_name_the_folder(tmp_path, fake_rtcl):
    scene = tmp_path / "somewhere" / "lake-10.json"   # read by the fake rtcl: not at all
    scene.parent.mkdir()
    scene.write_text("{}")   # but it must be a file: checked before the first run
    result = run_tool("--rtcl", fake_rtcl, "--quick", "--no-sweep", "--accel", "bvh",
                      "--scene", "somewhere/lake-10.json", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    (folder,) = (tmp_path / "rtcl-results").iterdir()   # no --out: a new folder there
    assert re.fullmatch(r"fake-gpu-bvh-lake-10-\d{8}-\d{6}", folder.name)
    calls = (fake_rtcl.parent / "calls").read_text().splitlines()
    assert len(calls) == 7
    assert all("--accel bvh" in call and "-s somewhere/lake-10.json" in call
               for call in calls)
    meta = json.loads((folder / "results.json").read_text())["meta"]
    # size and depth as rtcl reported them (the fake renders 4x4 whatever --size says)
    assert {key: meta[key] for key in ("accel", "scene", "scene_stem", "size", "depth")} \
        == {"accel": "bvh", "scene": "somewhere/lake-10.json", "scene_stem": "lake-10",
            "size": "4x4", "depth": 5}
    assert not list(tmp_path.rglob("*.npy"))


@pytest.mark.slow  # make test's 3 minutes (cold, 2-core VM)
def test_default_accel_is_none_in_the_device_folder(tmp_path, fake_rtcl):
    result = run_tool("--rtcl", fake_rtcl, "--quick", "--no-sweep", "--no-serial",
                      "--no-reference", "--peak-gflops", "500", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    (folder,) = (tmp_path / "rtcl-results").iterdir()
    assert re.fullmatch(r"fake-gpu-\d{8}-\d{6}", folder.name)
    # The peak is kept for --replot elsewhere, and bounds the kernels in table1.md.
    assert json.loads((folder / "results.json").read_text())["meta"]["peak"]["gflops"] == 500
    assert "## Bounds" in (folder / "table1.md").read_text()
    assert f"results in rtcl-results/{folder.name}" in result.stderr
    calls = (fake_rtcl.parent / "calls").read_text().splitlines()
    assert calls and all("--accel none" in call for call in calls)
    meta = json.loads((folder / "results.json").read_text())["meta"]
    assert (meta["accel"], meta["scene_stem"]) == ("none", "paper60")
    assert sorted(path.name for path in folder.iterdir()) == \
        ["histograms.png", "results.json", "speedup.png", "table1.md"]


@pytest.mark.slow  # make test's 3 minutes (cold, 2-core VM)
@pytest.mark.parametrize("how", ["matplotlib missing", "--no-plots"])
def test_without_figures_results_and_table_are_written(tmp_path, fake_rtcl, how):
    out = tmp_path / "out"
    stale = out / "speedup.png"    # a previous run's figure (untracked: removed)
    stale.parent.mkdir(parents=True)
    stale.write_bytes(b"old")
    options = ["--no-plots"] if how == "--no-plots" else []
    env = without_matplotlib(tmp_path) if how == "matplotlib missing" else None
    result = run_tool("--rtcl", fake_rtcl, "--quick", "--no-sweep", "--accel", "bvh",
                      "--out", out, *options, env=env)
    assert result.returncode == 0, result.stderr
    folder = stale.parent
    assert sorted(path.name for path in folder.iterdir()) == ["results.json", "table1.md"]
    notes = [line for line in result.stderr.splitlines() if "figures skipped" in line]
    assert len(notes) == 1
    assert f"tools/experiments.py --replot {folder}` on a machine with matplotlib" in notes[0]
    assert ("matplotlib cannot be imported" if env else "(--no-plots)") in notes[0]
    # The figures come back later from results.json alone.
    replotted = run_tool("--replot", folder)
    assert replotted.returncode == 0, replotted.stderr
    for name in ("speedup.png", "histograms.png"):
        assert (folder / name).read_bytes().startswith(PNG_SIGNATURE)


# ---- --replot of the results.json files committed before histograms were kept -------------

def committed_results(new_format):
    """The committed results.json files, those with meta['accel'] (made since
    --accel) or those without (made before histograms were kept)."""
    found = []
    for path in sorted((ROOT / "docs" / "results").glob("*/results.json")):
        if ("accel" in json.loads(path.read_text())["meta"]) == new_format:
            found.append(path)
    return found


def first_quick(paths):
    """Redrawing every committed folder takes a minute: the first folder is
    redrawn by make test, the others by make test-long."""
    return [pytest.param(path, marks=() if i == 0 else pytest.mark.slow)
            for i, path in enumerate(paths)]


COMMITTED = first_quick(committed_results(new_format=False))
COMMITTED_NEW = first_quick(committed_results(new_format=True))


@pytest.mark.parametrize("results", COMMITTED_NEW, ids=lambda path: path.parent.name)
def test_replot_of_a_committed_new_results_json_draws_every_figure(tmp_path, failing_rtcl,
                                                                   results):
    folder = tmp_path / results.parent.name
    shutil.copytree(results.parent, folder)
    for png in folder.glob("*.png"):
        png.unlink()
    (folder / "table1.md").unlink()
    result = run_tool("--rtcl", failing_rtcl, "--replot", folder)
    assert result.returncode == 0, result.stderr
    assert not (tmp_path / "rtcl-ran").exists()
    meta = json.loads(results.read_text())["meta"]
    heading, _ = heading_and_accel((folder / "table1.md").read_text())
    assert f"--accel {meta['accel']}" in heading
    for name in ("speedup.png", "histograms.png"):
        assert (folder / name).read_bytes().startswith(PNG_SIGNATURE)


@pytest.mark.parametrize("results", COMMITTED, ids=lambda path: path.parent.name)
def test_replot_of_a_committed_old_results_json(tmp_path, failing_rtcl, results):
    folder = tmp_path / results.parent.name
    shutil.copytree(results.parent, folder)
    (folder / "table1.md").unlink()
    (folder / "speedup.png").unlink()
    result = run_tool("--rtcl", failing_rtcl, "--replot", folder)
    assert result.returncode == 0, result.stderr
    assert not (tmp_path / "rtcl-ran").exists()
    heading, accel = heading_and_accel((folder / "table1.md").read_text())
    assert heading.startswith("# Table 1 reproduced: rtcl on ") and "--accel" not in heading
    assert "`--accel none`" in accel
    assert (folder / "speedup.png").read_bytes().startswith(PNG_SIGNATURE)
    for name in ("histograms.png", "histograms_best.png"):
        if (results.parent / name).exists():
            assert (folder / name).read_bytes() == (results.parent / name).read_bytes()
    assert "kept histograms.png" in result.stderr


def test_committed_old_and_new_results_exist():
    """The tests above must have something to replot."""
    assert len(COMMITTED) >= 2 and len(COMMITTED_NEW) >= 4


# ---- one --quick --accel bvh run of the real rtcl ----------------------------------------

def rtcl_missing():
    if not os.access(RTCL, os.X_OK):
        return f"{RTCL} is not built"
    help_text = subprocess.run([RTCL, "--help"], capture_output=True, text=True,
                               timeout=60).stdout
    return None if "--accel" in help_text else f"{RTCL} has no --accel"


@pytest.fixture(scope="module")
def bvh_study(tmp_path_factory):
    """Runs `experiments.py --quick --accel bvh` once (small image, sweep included);
    returns (folder, results.json, the run's stderr, a pristine copy of the folder)."""
    reason = rtcl_missing()
    if reason:
        pytest.skip(reason)
    out = tmp_path_factory.mktemp("study")
    result = run_tool("--rtcl", RTCL, "--quick", "--accel", "bvh", "--size", "40x32",
                      "--repeat", "1", cwd=out)
    assert result.returncode == 0, result.stderr
    (folder,) = (out / "rtcl-results").iterdir()
    pristine = out / "pristine"
    shutil.copytree(folder, pristine)
    return folder, json.loads((folder / "results.json").read_text()), result.stderr, pristine


@pytest.mark.slow
def test_bvh_study_folder_meta_and_table(bvh_study):
    folder, results, stderr, _ = bvh_study
    device = results["runs"][0]["stats"]["device"]
    assert re.fullmatch(re.escape(report.device_slug(device)) + r"-bvh-paper60-\d{8}-\d{6}",
                        folder.name)
    meta = results["meta"]
    assert (meta["accel"], meta["scene"], meta["scene_stem"], meta["size"], meta["depth"]) \
        == ("bvh", "paper60.json (built-in)", "paper60", "40x32", 5)
    assert {run["stats"]["accel"] for run in results["runs"]} == {"bvh"}
    assert all("--accel bvh" in run["command"] for run in results["runs"])
    heading, accel = heading_and_accel((folder / "table1.md").read_text())
    assert heading.endswith(", --accel bvh, scene paper60")
    assert "`--accel bvh`" in accel and "the CPU reference has no BVH" in accel
    assert sorted(path.name for path in folder.iterdir()) == \
        sorted(["results.json", "table1.md", *FIGURES])
    assert "figures skipped" not in stderr


@pytest.mark.slow
def test_bvh_study_keeps_every_runs_histogram_small(bvh_study):
    folder, results, _, _ = bvh_study
    assert (folder / "results.json").stat().st_size < 200_000
    for run in results["runs"]:
        stats, stored = run["stats"], run.get("flops_histogram")
        if run["kernel"] == "reference":
            assert stored is None
            continue
        assert len(stored["counts"]) == histogram.DEFAULT_BINS, run["command"]
        items = stats["global_size"][0] * stats["global_size"][1]
        if run["kernel"] == "wavefront":     # every launch's work-items
            assert stored["work_items"] > items
        else:
            assert stored["work_items"] == items
        assert sum(stored["counts"]) == stored["work_items"]
        spread = stats["flops_per_item"]
        assert (stored["max"], stored["min"]) == (spread["max"], spread["min"])
        assert stored["mean"] == pytest.approx(spread["mean"], rel=1e-6)
        assert stored["mean"] * stored["work_items"] == pytest.approx(stats["total_flops"])
    best = [run for run in results["runs"] if run["role"] == "best"]
    assert best and all(run["flops_histogram"] for run in best)


@pytest.mark.slow
def test_bvh_study_replot_redraws_every_figure_from_results_json(bvh_study, tmp_path,
                                                                  failing_rtcl):
    _, _, _, pristine = bvh_study
    folder = tmp_path / "copy"
    shutil.copytree(pristine, folder)
    for name in FIGURES:
        (folder / name).unlink()
    result = run_tool("--rtcl", failing_rtcl, "--replot", folder)
    assert result.returncode == 0, result.stderr
    assert not (tmp_path / "rtcl-ran").exists()
    for name in FIGURES:
        assert (folder / name).read_bytes().startswith(PNG_SIGNATURE), name
    # The same data through the same drawing code: the very figure the run drew.
    assert (folder / "histograms.png").read_bytes() == \
        (pristine / "histograms.png").read_bytes()
    assert "kept" not in result.stderr


@pytest.mark.slow
def test_bvh_study_replot_without_matplotlib_rewrites_the_table(bvh_study, tmp_path):
    _, _, _, pristine = bvh_study
    folder = tmp_path / "copy"
    shutil.copytree(pristine, folder)
    (folder / "table1.md").unlink()
    result = run_tool("--replot", folder, env=without_matplotlib(tmp_path))
    assert result.returncode == 0, result.stderr
    assert "regenerated on" in (folder / "table1.md").read_text()
    assert "figures skipped (matplotlib cannot be imported" in result.stderr
    for name in FIGURES:    # left as they were
        assert (folder / name).read_bytes() == (pristine / name).read_bytes()


def test_rtcl_commit_names_the_commit_of_a_copied_tree(monkeypatch):
    """A GPU machine's copy has a stale git HEAD: RTCL_COMMIT names the real one."""
    from rtcl_tools import report
    monkeypatch.setenv("RTCL_COMMIT", "deff42a")
    assert report.git_commit() == "deff42a"
    monkeypatch.delenv("RTCL_COMMIT")
    assert report.git_commit() != "deff42a"
