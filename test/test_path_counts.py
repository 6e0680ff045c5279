"""The counting run's paths (docs/RENDERING.md, "Paths per bounce"; issue 41):
every path counted once by its length in segments, the live paths per bounce
derived from them, the same figures from every kernel, and the summary's
`paths:` line saying what --stats says. On any OpenCL device (PoCL here)."""
import json
import os
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
BOX = ROOT / "test" / "scenes" / "path_box.json"
BINS = 16


def counted(tmp_path, scene, kernel, size="12x12", spp=3, *args):
    """One counting render: returns (its --stats, its stdout)."""
    stats = tmp_path / f"{kernel}.json"
    result = subprocess.run([RTCL, str(scene), "-k", kernel, "--size", size, "--spp", str(spp),
                             "-o", str(tmp_path / f"{kernel}.pfm"), "--flops",
                             str(tmp_path / f"{kernel}.npy"), "--stats", str(stats), *args],
                            capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert result.returncode == 0, result.stderr
    return json.loads(stats.read_text()), result.stdout


def check_paths(paths, count, max_depth):
    """What holds of any render's paths: every path counted once, lengths
    1 ... max_depth + 2, live paths the tail sums of the histogram."""
    hist = paths["length_histogram"]
    assert paths["length_bins"] == BINS and len(hist) == BINS
    assert paths["count"] == sum(hist) == count
    assert 1 <= paths["max_length"] <= max_depth + 2
    assert hist[paths["max_length"] - 1] > 0
    assert all(n == 0 for n in hist[paths["max_length"]:])
    assert paths["segments"] == sum((b + 1) * n for b, n in enumerate(hist))
    assert paths["mean_length"] == pytest.approx(paths["segments"] / count)
    live = paths["live_per_bounce"]
    assert len(live) == paths["max_length"]
    assert live == [sum(hist[b:]) for b in range(len(live))]
    assert live[0] == count                      # every path traces its primary ray
    assert all(a >= b for a, b in zip(live, live[1:]))


def test_every_path_is_counted_once_by_its_length(tmp_path):
    stats, summary = counted(tmp_path, BOX, "dynamic")
    paths = stats["paths"]
    check_paths(paths, 12 * 12 * 3, 6)
    # The box is closed but for its front: paths bounce, so some are long.
    assert paths["max_length"] > 3
    # A segment is a ray; so is a shadow ray, which is not a segment.
    assert stats["rays"] > paths["segments"]
    assert stats["simd_efficiency_measured"] == "not measurable on this device"
    # The summary says what --stats says.
    line = re.search(r"^paths: +(\d+), ([\d.]+) segments each on average, at most (\d+); "
                     r"live at bounce 0, 1, \.\.\.: (.*)$", summary, re.MULTILINE)
    assert line, summary
    assert int(line.group(1)) == paths["count"]
    assert line.group(2) == f"{paths['mean_length']:.2f}"
    assert int(line.group(3)) == paths["max_length"]
    shares = [float(s.rstrip("%")) for s in line.group(4).split(", ")]
    assert shares == [round(100 * n / paths["count"], 1) for n in paths["live_per_bounce"]]


@pytest.mark.slow  # make test's 3 minutes: test_path.py's counts test is slow too
def test_dynamic_and_wavefront_count_the_same_paths(tmp_path):
    dynamic, _ = counted(tmp_path, BOX, "dynamic")
    wavefront, _ = counted(tmp_path, BOX, "wavefront")
    assert dynamic["paths"] == wavefront["paths"]
    assert dynamic["total_flops"] == wavefront["total_flops"]


# Schedules of other branches (issue 41: path regeneration, the wavefront in
# stages), counted too where this rtcl takes their options.
OPTIONAL_SCHEDULES = [["-k", "persistent", "--regenerate", "--fetch", "item"],
                      ["-k", "persistent", "--regenerate", "--fetch", "subgroup"],
                      ["-k", "wavefront", "--wavefront-form", "stages"]]


def accepted(tmp_path, options):
    """Whether this rtcl renders with options (a tiny probe)."""
    return subprocess.run([RTCL, str(BOX), *options, "--size", "4x4", "--spp", "1", "-q", "-o",
                           str(tmp_path / "probe.pfm")], capture_output=True,
                          timeout=300).returncode == 0


@pytest.mark.slow
def test_every_kernel_counts_the_same_paths(tmp_path):
    first = None
    schedules = [["-k", k] for k in ["serial", "naive", "cyclic", "dynamic", "persistent",
                                     "wavefront"]]
    schedules += [o for o in OPTIONAL_SCHEDULES if accepted(tmp_path, o)]
    for options in schedules:
        stats, _ = counted(tmp_path, BOX, options[1], "10x8", 2, *options[2:])
        check_paths(stats["paths"], 10 * 8 * 2, 6)
        figures = (stats["paths"], stats["total_flops"], stats["rays"])
        assert first is None or figures == first, options
        first = figures


@pytest.mark.slow
def test_max_depth_bounds_the_lengths(tmp_path):
    doc = json.loads(BOX.read_text())
    doc["max_depth"] = 1
    scene = tmp_path / "depth1.json"
    scene.write_text(json.dumps(doc))
    stats, _ = counted(tmp_path, scene, "dynamic")
    check_paths(stats["paths"], 12 * 12 * 3, 1)
    # Vertex 1's ray, which looks only for emitters, is the third segment:
    # inside the closed box every path that hits its walls reaches it.
    assert stats["paths"]["max_length"] == 3


@pytest.mark.slow
def test_whitted_renders_count_no_paths(tmp_path):
    stats, summary = counted(tmp_path, BOX, "dynamic", "12x12", 1, "--integrator", "whitted")
    assert "paths" not in stats
    assert "paths:" not in summary


def test_pieces_count_the_paths_of_one_launch(tmp_path):
    """Row bands and samples split over pieces (the multi-device path, here
    one device) add up to the one launch's paths."""
    one, _ = counted(tmp_path, BOX, "dynamic")
    bands, _ = counted(tmp_path, BOX, "dynamic", "12x12", 3, "--devices", "0:0",
                       "--piece-rows", "4")
    samples, _ = counted(tmp_path, BOX, "dynamic", "12x12", 3, "--devices", "0:0",
                         "--split", "samples")
    assert bands["paths"] == one["paths"] and samples["paths"] == one["paths"]


def test_paths_longer_than_the_bins_go_to_the_last(tmp_path):
    """Beyond RT_PATH_LENGTH_BINS segments the histogram's last bin takes
    the paths; the count, the longest and the segments stay exact."""
    doc = json.loads(BOX.read_text())
    doc["max_depth"] = 40
    for material in doc["materials"].values():     # bright walls: long paths
        if "reflectance" in material.get("bsdf", {}):
            material["bsdf"]["reflectance"] = [0.95, 0.95, 0.95]
    scene = tmp_path / "deep.json"
    scene.write_text(json.dumps(doc))
    stats, _ = counted(tmp_path, scene, "dynamic", "16x16", 4)
    paths = stats["paths"]
    hist, live = paths["length_histogram"], paths["live_per_bounce"]
    assert paths["max_length"] > BINS and hist[-1] > 0
    assert paths["count"] == sum(hist) == 16 * 16 * 4
    assert len(live) == BINS and live[-1] == hist[-1]
    # The paths of 16 or more segments have at least 16 each.
    assert paths["segments"] >= sum((b + 1) * n for b, n in enumerate(hist))
    assert paths["segments"] > sum((b + 1) * n for b, n in enumerate(hist[:-1])) + BINS * hist[-1] - 1
