"""--schedule-map FILE (docs/RENDERING.md, "The schedule map"): which
work-group and work-item traced each pixel, and in which order the pixels
were started, as a .npy array or a picture coloured by work-group; the
instrumented run gives the same image; what it cannot record is refused with
one message and nothing written."""
import os
import pathlib
import subprocess
import sys

import pytest

np = pytest.importorskip("numpy")

ROOT = pathlib.Path(__file__).resolve().parent.parent
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
sys.path.insert(0, str(ROOT / "tools"))
from rtcl_tools import ppm  # noqa: E402

SMALL = ["--size", "48x32", "-w", "8x4"]


def rtcl(*args, cwd):
    return subprocess.run([RTCL, *SMALL, *args], capture_output=True, text=True, cwd=cwd,
                          timeout=300)


@pytest.mark.parametrize("kernel", ["serial", "naive", "cyclic", "dynamic", "persistent"])
def test_the_npy_holds_group_item_and_ticket_of_every_pixel(tmp_path, kernel):
    result = rtcl("-q", "-k", kernel, "-o", "map.ppm", "--schedule-map", "s.npy", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    plain = rtcl("-q", "-k", kernel, "-o", "plain.ppm", cwd=tmp_path)
    assert plain.returncode == 0, plain.stderr
    assert (tmp_path / "map.ppm").read_bytes() == (tmp_path / "plain.ppm").read_bytes()
    s = np.load(tmp_path / "s.npy")
    assert s.shape == (32, 48, 3) and s.dtype == np.uint32
    tickets = np.sort(s[..., 2].ravel())
    assert np.array_equal(tickets, np.arange(48 * 32))
    assert s[..., 1].max() < 32  # items of an 8x4 group
    if kernel == "naive":
        y, x = np.mgrid[0:32, 0:48]
        assert np.array_equal(s[..., 0], (y // 4) * 6 + x // 8)


def test_the_picture_colours_pixels_by_work_group(tmp_path):
    result = rtcl("-q", "-k", "naive", "-o", "x.ppm", "--schedule-map", "s.ppm", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    (width, height), data = ppm.pixels(tmp_path / "s.ppm")
    assert (width, height) == (48, 32)
    rgb = np.frombuffer(data, dtype=np.uint8).reshape(height, width, 3)
    # Each 8x4 group one colour, 6x8 groups, and neighbours differ.
    for gy in range(8):
        for gx in range(6):
            block = rgb[4 * gy:4 * gy + 4, 8 * gx:8 * gx + 8].reshape(-1, 3)
            assert (block == block[0]).all()
    colours = {tuple(rgb[4 * gy, 8 * gx]) for gy in range(8) for gx in range(6)}
    assert len(colours) > 40


def test_the_summary_names_the_schedule_map(tmp_path):
    result = rtcl("-k", "dynamic", "-o", "x.ppm", "--schedule-map", "s.npy", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "output:  x.ppm, schedule map s.npy" in result.stdout


@pytest.mark.parametrize("args, message", [
    (["-k", "wavefront"], "--schedule-map records which work-item traced each pixel: the "
     "wavefront's work-items take rays, not pixels, and every bounce hands them out anew; "
     "choose serial, naive, cyclic, dynamic or persistent"),
    (["-k", "reference"], "--schedule-map records which work-item traced each pixel: the "
     "reference renderer has none; choose serial, naive, cyclic, dynamic or persistent"),
    (["-k", "naive", "--frames", "0:1"], "--schedule-map records one device's launches over "
     "the whole image: it does not apply to --frames"),
    (["-k", "naive", "--devices", "0:0"], "--schedule-map records one device's launches over "
     "the whole image: it does not apply to --devices"),
])
def test_what_it_cannot_record_is_refused(tmp_path, args, message):
    result = rtcl(*args, "-o", "x.ppm", "--schedule-map", "s.npy", cwd=tmp_path)
    assert result.returncode == 2
    assert result.stderr == "rtcl: " + message + "\n"
    assert list(tmp_path.iterdir()) == []


def test_the_schedule_map_and_the_image_cannot_share_a_file(tmp_path):
    result = rtcl("-k", "naive", "-o", "x.ppm", "--schedule-map", "./x.ppm", cwd=tmp_path)
    assert result.returncode == 2
    assert "-o/--output x.ppm and --schedule-map ./x.ppm name the same file" in result.stderr
    assert list(tmp_path.iterdir()) == []


REPLAY = [sys.executable, str(ROOT / "tools" / "schedule_replay.py")]


def test_the_replay_is_a_gif_of_the_maps_side_by_side(tmp_path):
    pytest.importorskip("PIL")
    from PIL import Image
    for kernel in ("naive", "dynamic"):
        result = rtcl("-q", "-k", kernel, "-o", kernel + ".ppm", "--schedule-map",
                      kernel + ".npy", cwd=tmp_path)
        assert result.returncode == 0, result.stderr
    result = subprocess.run([*REPLAY, "naive.npy", "dynamic.npy", "-o", "r.gif", "--frames",
                             "6"], capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert result.returncode == 0, result.stderr
    gif = Image.open(tmp_path / "r.gif")
    assert gif.n_frames == 6
    assert gif.size == (48 + 8 + 48, 32 + 16)
    # The first frame shows a sixth of each image, the last all of it, in
    # the colours of the --schedule-map picture.
    first = np.asarray(gif.convert("RGB"))[16:, :48]
    gif.seek(5)
    last = np.asarray(gif.convert("RGB"))[16:, :48]
    unstarted = (first == (40, 40, 40)).all(axis=2).sum()
    assert unstarted == 48 * 32 - 48 * 32 // 6
    assert not (last == (40, 40, 40)).all(axis=2).any()
    picture = rtcl("-q", "-k", "naive", "-o", "x.ppm", "--schedule-map", "p.ppm", cwd=tmp_path)
    assert picture.returncode == 0, picture.stderr
    (_, _), data = ppm.pixels(tmp_path / "p.ppm")
    assert np.array_equal(last, np.frombuffer(data, dtype=np.uint8).reshape(32, 48, 3))


def test_the_replay_refuses_what_is_not_a_schedule_map(tmp_path):
    np.save(tmp_path / "flops.npy", np.zeros((4, 4), dtype="<u8"))
    result = subprocess.run([*REPLAY, "flops.npy", "-o", "r.gif"], capture_output=True,
                            text=True, cwd=tmp_path, timeout=120)
    assert result.returncode == 1
    assert "flops.npy: not a schedule map (dtype uint64, shape (4, 4)" in result.stderr
    assert not (tmp_path / "r.gif").exists()
    result = subprocess.run([*REPLAY, "flops.npy", "-o", "r.mp4"], capture_output=True,
                            text=True, cwd=tmp_path, timeout=120)
    assert result.returncode == 2
    assert "write a .gif" in result.stderr


@pytest.mark.parametrize("kernel, low, high", [("serial", 1 / 32, 1 / 32), ("naive", 0.2, 1.0)])
def test_flops_and_schedule_together_model_the_simd_efficiency(tmp_path, kernel, low, high):
    import json
    result = rtcl("-k", kernel, "-o", "x.ppm", "--work-map", "w.npy", "--schedule-map",
                  "s.npy", "--stats", "st.json", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    stats = json.loads((tmp_path / "st.json").read_text())
    efficiency = stats["simd_efficiency_model"]
    assert low - 1e-12 <= efficiency <= high + 1e-12
    assert stats["warp_width"] == 32
    assert stats["work_items_used"] == (1 if kernel == "serial" else 48 * 32)
    assert f"; modelled {100 * efficiency:.1f}% (warps of 32 in lock-step" in result.stdout
    assert f"{stats['work_items_used']} of " in result.stdout
    assert "simd:    not measurable on this device; " in result.stdout  # PoCL
    # The model from the two files, as docs/RENDERING.md defines it.
    flops, schedule = np.load(tmp_path / "w.npy"), np.load(tmp_path / "s.npy")
    group, item, ticket = (schedule[..., i].ravel().astype(np.int64) for i in range(3))
    order = np.lexsort((ticket, item, group))
    step = np.zeros(order.size, dtype=np.int64)
    for k in range(1, order.size):
        a, b = order[k - 1], order[k]
        if group[a] == group[b] and item[a] == item[b]:
            step[k] = step[k - 1] + 1
    cost = {}
    for k, p in enumerate(order):
        key = (group[p], item[p] // 32, step[k])
        cost[key] = max(cost.get(key, 0), int(flops.ravel()[p]))
    assert stats["warp_steps"] == len(cost)
    assert efficiency == pytest.approx(int(flops.sum()) / (32 * sum(cost.values())), rel=1e-8)


def test_without_flops_there_is_no_model(tmp_path):
    result = rtcl("-k", "naive", "-o", "x.ppm", "--schedule-map", "s.npy", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "simd:" not in result.stdout  # no counting run


def test_no_group_colour_is_near_the_replays_not_started_grey(tmp_path):
    # Issue 44: a group coloured (38, 38, 38) looked like the replay's "not
    # started" (40, 40, 40). Every group's brightest channel is 0.45 or more.
    from rtcl_tools.commands.schedule_replay import UNSTARTED, group_colours
    colours = group_colours(np.arange(1 << 20, dtype=np.uint32)).astype(int)
    assert colours.max(axis=1).min() >= round(0.45 * 255)
    assert np.abs(colours - np.array(UNSTARTED)).max(axis=1).min() >= 70
    # rtcl's picture gives the same colours: one group a pixel, 1536 groups.
    result = subprocess.run([RTCL, "-q", "--size", "48x32", "-w", "1x1", "-k", "naive", "-o",
                             "x.ppm", "--schedule-map", "p.ppm"], cwd=tmp_path,
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    result = subprocess.run([RTCL, "-q", "--size", "48x32", "-w", "1x1", "-k", "naive", "-o",
                             "x.ppm", "--schedule-map", "s.npy"], cwd=tmp_path,
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    (_, _), data = ppm.pixels(tmp_path / "p.ppm")
    picture = np.frombuffer(data, dtype=np.uint8).reshape(32, 48, 3)
    assert np.array_equal(picture, group_colours(np.load(tmp_path / "s.npy")[..., 0]))
