"""rtcl-maps (tools/maps.py): the work map and the schedule map of a render in one
figure, each panel with its colour bar and labelled axes; every bad input one line
on stderr, exit status 1 and no figure.  Small hand-made maps, plus one run of the
built ./rtcl (or $RTCL) on PoCL."""
import os
import pathlib
import subprocess
import sys

import pytest

np = pytest.importorskip("numpy")
pytest.importorskip("matplotlib")

ROOT = pathlib.Path(__file__).resolve().parent.parent
TOOLS = ROOT / "tools"
RTCL = os.environ.get("RTCL", str(ROOT / "rtcl"))
sys.path.insert(0, str(TOOLS))

from rtcl_tools import pieces as pieces_module  # noqa: E402
from rtcl_tools import schedule  # noqa: E402
from rtcl_tools.commands import maps  # noqa: E402

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
HEIGHT, WIDTH = 6, 8
UNSTARTED = 0xFFFFFFFF


def work_map(largest=68_000):
    """Flops per pixel, row y costing y / (HEIGHT - 1) of largest, pixel (0, 0) none."""
    rows = np.linspace(0, largest, HEIGHT).astype("<u8")
    work = np.repeat(rows[:, None], WIDTH, axis=1)
    work[0, 0] = 0
    return work


def schedule_map(unstarted=((5, 7), (5, 6))):
    """Six work-groups of 4x2 pixels (width x height), tickets row by row; the
    pixels of unstarted never started."""
    y, x = np.mgrid[0:HEIGHT, 0:WIDTH]
    schedule = np.zeros((HEIGHT, WIDTH, 3), dtype="<u4")
    schedule[..., 0] = (y // 2) * 2 + x // 4
    schedule[..., 1] = (y % 2) * 4 + x % 4
    schedule[..., 2] = y * WIDTH + x
    for pixel in unstarted:
        schedule[pixel] = UNSTARTED
    return schedule


def run_maps(*args, cwd):
    return subprocess.run([sys.executable, str(TOOLS / "maps.py"), *map(str, args)],
                          capture_output=True, text=True, cwd=cwd, timeout=120)


@pytest.fixture
def inputs(tmp_path):
    np.save(tmp_path / "w.npy", work_map())
    np.save(tmp_path / "s.npy", schedule_map())
    return tmp_path


def drawn(work=None, schedule=None, **options):
    """The image axes of the figure draw_maps draws, left to right."""
    from matplotlib.figure import Figure
    figure = Figure()
    maps.draw_maps(figure, work, schedule, **options)
    return figure, [axes for axes in figure.axes if axes.images]


def colour_bar_label(axes):
    return axes.images[0].colorbar.ax.get_ylabel()


@pytest.mark.parametrize("options, suffix", [(["--log", "--title", "t"], ".png"),
                                             ([], ".svg"), ([], ".pdf")])
def test_the_figure_is_written_in_the_format_of_its_name(inputs, options, suffix):
    result = run_maps("--work", "w.npy", "--schedule", "s.npy", "-o", "maps" + suffix,
                      *options, cwd=inputs)
    assert result.returncode == 0, result.stderr
    assert result.stderr == ""
    data = (inputs / ("maps" + suffix)).read_bytes()
    assert data.startswith({".png": PNG_SIGNATURE, ".svg": b"<?xml", ".pdf": b"%PDF"}[suffix])
    assert [p.name for p in inputs.iterdir() if p.name.startswith(".")] == []


def test_the_panels_are_labelled_as_the_docs_say():
    figure, panels = drawn(work_map(), schedule_map(), title="a render")
    assert [axes.get_title() for axes in panels] == [
        "work per pixel", "work-group per pixel", "order pixels were started"]
    assert [colour_bar_label(axes) for axes in panels] == [
        "flops per pixel (kFLOP)", "work-group", "order started (share of pixels)"]
    for axes in panels:
        assert (axes.get_xlabel(), axes.get_ylabel()) == ("pixel x", "pixel y")
        # As rendered: row 0 at the top.
        assert axes.images[0].origin == "upper"
        assert axes.get_ylim()[0] > axes.get_ylim()[1]
    assert figure._suptitle.get_text() == "a render"
    # Six axes: three panels and their colour bars.
    assert len(figure.axes) == 6


def test_one_map_alone_draws_its_own_panels():
    _, panels = drawn(work=work_map(500))
    assert [colour_bar_label(axes) for axes in panels] == ["flops per pixel (FLOP)"]
    _, panels = drawn(schedule=schedule_map())
    assert [colour_bar_label(axes) for axes in panels] == [
        "work-group", "order started (share of pixels)"]


def test_the_work_is_drawn_in_its_flop_unit():
    _, (work, *_) = drawn(work_map(68_000))
    values = work.images[0].get_array()
    assert values.max() == pytest.approx(68.0)
    assert work.images[0].norm.vmin == 0


def test_a_log_scale_shows_pixels_of_no_work_in_the_lowest_colour():
    _, (work,) = drawn(work_map(68_000), log=True)
    image = work.images[0]
    assert colour_bar_label(work) == "flops per pixel (kFLOP, log scale)"
    assert type(image.norm).__name__ == "LogNorm"
    cheapest = 68_000 / (HEIGHT - 1) / 1000
    assert image.norm.vmin == pytest.approx(cheapest)
    values = np.ma.getdata(image.get_array())
    assert values[0, 0] == pytest.approx(cheapest)
    assert not np.ma.is_masked(image.get_array())


def test_the_order_is_a_share_of_the_started_pixels_and_unstarted_pixels_are_masked():
    _, (groups, order) = drawn(schedule=schedule_map())
    shares = order.images[0].get_array()
    assert shares.min() == 0 and shares.max() == 1
    assert ((shares >= 0) & (shares <= 1)).all()
    started = HEIGHT * WIDTH - 2
    assert shares.count() == started
    assert shares[0, 1] == pytest.approx(1 / (started - 1))
    for axes in (groups, order):
        mask = np.ma.getmaskarray(axes.images[0].get_array())
        assert mask[5, 7] and mask[5, 6] and mask.sum() == 2
        assert axes.images[0].cmap.get_bad().tolist() == pytest.approx([0.6, 0.6, 0.6, 1.0])
    assert groups.images[0].get_array().max() == 5


def assert_refused(result, inputs, output, *fragments):
    assert result.returncode == 1, (result.returncode, result.stderr)
    lines = result.stderr.splitlines()
    assert len(lines) == 1, result.stderr
    assert lines[0].startswith("maps.py: error: "), lines[0]
    for fragment in fragments:
        assert fragment in lines[0]
    assert not (inputs / output).exists()
    assert [p.name for p in inputs.iterdir() if p.name.startswith(".")] == []


def test_a_missing_map_is_refused(inputs):
    assert_refused(run_maps("--work", "no.npy", "--schedule", "s.npy", "-o", "m.png",
                            cwd=inputs), inputs, "m.png", "no.npy: no such file")
    assert_refused(run_maps("--schedule", "none.npy", "-o", "m.png", cwd=inputs), inputs,
                   "m.png", "none.npy: no such file")


def test_what_is_not_a_npy_is_refused(inputs):
    (inputs / "text.npy").write_text("P6 8 6 255\n")
    for option in ("--work", "--schedule"):
        assert_refused(run_maps(option, "text.npy", "-o", "m.png", cwd=inputs), inputs,
                       "m.png", "text.npy: not a .npy file (no NumPy header)")


def test_a_map_of_the_wrong_kind_is_refused(inputs):
    np.save(inputs / "f.npy", np.zeros((HEIGHT, WIDTH), dtype="<f4"))
    assert_refused(run_maps("--work", "f.npy", "-o", "m.png", cwd=inputs), inputs, "m.png",
                   "f.npy: not a work map (dtype float32, shape (6, 8); rtcl --work-map "
                   "FILE.npy writes uint64, height x width)")
    assert_refused(run_maps("--work", "s.npy", "-o", "m.png", cwd=inputs), inputs, "m.png",
                   "s.npy: not a work map (dtype uint32, shape (6, 8, 3)")
    assert_refused(run_maps("--schedule", "w.npy", "-o", "m.png", cwd=inputs), inputs,
                   "m.png", "w.npy: not a schedule map (dtype uint64, shape (6, 8); rtcl "
                   "--schedule-map writes uint32, height x width x 3)")


def test_maps_of_two_sizes_are_refused(inputs):
    np.save(inputs / "small.npy", work_map()[:4])
    assert_refused(run_maps("--work", "small.npy", "--schedule", "s.npy", "-o", "m.png",
                            cwd=inputs), inputs, "m.png",
                   "the work map small.npy is 4x8 (height x width) but the schedule map "
                   "s.npy is 6x8")


def test_an_output_format_other_than_png_svg_pdf_is_refused(inputs):
    assert_refused(run_maps("--work", "w.npy", "-o", "m.gif", cwd=inputs), inputs, "m.gif",
                   "m.gif: output must end in .png, .svg, .pdf")


def test_a_figure_tracked_by_git_is_replaced_only_with_update_committed(inputs):
    git = ["git", "-c", "user.name=t", "-c", "user.email=t@t"]
    (inputs / "m.png").write_bytes(b"committed")
    for command in (["init", "-q"], ["add", "m.png"], ["commit", "-q", "-m", "x"]):
        subprocess.run(git + command, cwd=inputs, check=True, capture_output=True)
    result = run_maps("--work", "w.npy", "-o", "m.png", cwd=inputs)
    assert result.returncode == 1
    assert result.stderr.startswith("maps.py: error: m.png is tracked by git: not overwritten")
    assert (inputs / "m.png").read_bytes() == b"committed"
    result = run_maps("--work", "w.npy", "-o", "m.png", "--update-committed", cwd=inputs)
    assert result.returncode == 0, result.stderr
    assert (inputs / "m.png").read_bytes().startswith(PNG_SIGNATURE)


def test_without_a_map_it_is_a_usage_error(inputs):
    result = run_maps("-o", "m.png", cwd=inputs)
    assert result.returncode == 2
    assert "give --work WORK.npy, --schedule SCHED.npy, --pieces STATS.json or several" \
        in result.stderr
    assert not (inputs / "m.png").exists()


def test_the_maps_of_one_rtcl_run_in_one_figure(tmp_path):
    render = subprocess.run([RTCL, "-k", "dynamic", "--size", "64x48", "--work-map", "w.npy",
                             "--schedule-map", "s.npy", "-q", "-o", "img.ppm"],
                            capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert render.returncode == 0, render.stderr
    result = run_maps("--work", "w.npy", "--schedule", "s.npy", "-o", "maps.png",
                      cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "maps.png").read_bytes().startswith(PNG_SIGNATURE)
    _, (work, groups, order) = drawn(maps.load_work_map(tmp_path / "w.npy"),
                                     schedule.load_map(tmp_path / "s.npy"))
    assert work.images[0].get_array().shape == (48, 64)
    # Every pixel was started: nothing masked, the order from 0 to 1.
    shares = order.images[0].get_array()
    assert shares.count() == 48 * 64 and shares.min() == 0 and shares.max() == 1


# ---- --pieces: one image over several devices (rtcl --devices --stats) -----------------

def pieces_stats(band=2, bands=3, classes=2):
    """A --stats document of an 8x6 image in two pieces of three split rows each, the
    rows in bands of 2 dealt to 2 classes: device 0 takes image bands 0 and 2 (rows
    0-1, 4-5), device 1 band 1 (rows 2-3)... in split rows 0-2 and 3-5."""
    return {"width": WIDTH, "height": HEIGHT, "multidevice": {
        "row_order": "interleave", "row_band": band, "row_bands": bands,
        "row_classes": classes,
        "devices": [{"device": "CPU A (PoCL)"}, {"device": "CPU B (PoCL)"}],
        "pieces": [
            {"device": 0, "x0": 0, "y0": 0, "width": WIDTH, "height": 4, "start_ms": 0.5,
             "end_ms": 3.0, "kernel_ms": 2.0},
            {"device": 1, "x0": 0, "y0": 4, "width": WIDTH, "height": 2, "start_ms": 0.7,
             "end_ms": 2.0, "kernel_ms": 1.0}]}}


def test_the_device_map_follows_the_row_map():
    owner = pieces_module.device_map(pieces_stats())
    # Split rows 0-3 are bands 0 and 2 (class 0): image rows 0-1 and 4-5.
    assert owner[:, 0].tolist() == [0, 0, 1, 1, 0, 0]
    # In scan order the same pieces are contiguous.
    scan = pieces_stats(band=0, bands=0, classes=0)
    assert pieces_module.device_map(scan)[:, 0].tolist() == [0, 0, 0, 0, 1, 1]
    # rt_piece_row's rule, with a remainder: 11 bands of 4 in 3 classes.
    assert [pieces_module.image_row(v, 4, 11, 3) for v in range(10, 20)] == \
        [26, 27, 36, 37, 38, 39, 4, 5, 6, 7]


def test_pieces_that_overlap_or_leave_the_image_are_refused(tmp_path):
    import json
    stats = pieces_stats()
    stats["multidevice"]["pieces"][1]["y0"] = 3  # split row 3 twice
    (tmp_path / "twice.json").write_text(json.dumps(stats))
    assert_refused(run_maps("--pieces", "twice.json", "-o", "m.png", cwd=tmp_path), tmp_path,
                   "m.png", "twice.json: piece 1 covers pixels another piece covers")
    stats["multidevice"]["pieces"][1]["y0"] = 5
    (tmp_path / "out.json").write_text(json.dumps(stats))
    assert_refused(run_maps("--pieces", "out.json", "-o", "m.png", cwd=tmp_path), tmp_path,
                   "m.png", "out.json: piece 1 (8x2 at 0, 5) leaves the 8x6 image")
    (tmp_path / "plain.json").write_text(json.dumps({"width": 8, "height": 6}))
    assert_refused(run_maps("--pieces", "plain.json", "-o", "m.png", cwd=tmp_path), tmp_path,
                   "m.png", "plain.json: no pieces of an image; write them with rtcl --devices")
    split = pieces_stats()
    split["multidevice"]["split"] = "samples"  # but no piece says its samples
    (tmp_path / "split.json").write_text(json.dumps(split))
    assert_refused(run_maps("--pieces", "split.json", "-o", "m.png", cwd=tmp_path), tmp_path,
                   "m.png", "split.json: samples split without each piece's samples")
    (tmp_path / "bad.json").write_text("{")
    assert_refused(run_maps("--pieces", "bad.json", "-o", "m.png", cwd=tmp_path), tmp_path,
                   "m.png", "bad.json: not rtcl --stats JSON")


def test_pieces_of_another_size_than_the_maps_are_refused(inputs):
    import json
    stats = pieces_stats()
    stats["height"] = 4
    (inputs / "p.json").write_text(json.dumps(stats))
    assert_refused(run_maps("--work", "w.npy", "--pieces", "p.json", "-o", "m.png",
                            cwd=inputs), inputs, "m.png",
                   "the work map w.npy is 6x8 (height x width) but the pieces of p.json is 4x8")


def test_the_pieces_panels_show_devices_and_time():
    figure, images = drawn(pieces=pieces_stats())
    [devices] = images
    assert devices.get_title() == "device per pixel"
    assert colour_bar_label(devices) == "device"
    assert devices.images[0].get_array()[:, 0].tolist() == [0, 0, 1, 1, 0, 0]
    [timeline] = [axes for axes in figure.axes if axes.get_title() == "pieces over time"]
    assert timeline.get_xlabel() == "ms from the frame's start"
    labels = [label.get_text() for label in timeline.get_yticklabels()]
    assert labels == ["0: CPU A (PoCL)", "1: CPU B (PoCL)"]
    extents = [path.get_extents() for bars in timeline.collections for path in bars.get_paths()]
    bars = sorted((round(box.x0, 3), round(box.width, 3)) for box in extents)
    assert bars == [(0.5, 2.5), (0.7, 1.3)]


def test_the_pieces_of_one_rtcl_run(tmp_path):
    render = subprocess.run([RTCL, "--devices", "0:0,0:1", "--size", "24x48", "-w", "8x4",
                             "-q", "-o", "img.ppm", "--stats", "s.json"],
                            capture_output=True, text=True, cwd=tmp_path, timeout=300,
                            env={**os.environ, "POCL_DEVICES": "pthread pthread"})
    assert render.returncode == 0, render.stderr
    result = run_maps("--pieces", "s.json", "-o", "maps.png", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "maps.png").read_bytes().startswith(PNG_SIGNATURE)
    owner = pieces_module.device_map(pieces_module.load_pieces(tmp_path / "s.json"))
    assert owner.shape == (48, 24) and (owner >= 0).all()


def test_split_samples_show_each_devices_samples():
    # rtcl --split samples: two pieces of the whole image, samples [0, 12)
    # and [12, 16): no device per pixel, but each device's samples.
    stats = pieces_stats(band=0, bands=0, classes=0)
    stats["multidevice"]["split"] = "samples"
    stats["multidevice"]["pieces"] = [
        {"device": 0, "x0": 0, "y0": 0, "width": WIDTH, "height": HEIGHT, "samples": [0, 12],
         "start_ms": 0.0, "end_ms": 3.0, "kernel_ms": 2.9},
        {"device": 1, "x0": 0, "y0": 0, "width": WIDTH, "height": HEIGHT, "samples": [12, 16],
         "start_ms": 0.0, "end_ms": 2.9, "kernel_ms": 2.8}]
    figure, images = drawn(pieces=stats)
    assert images == []  # no device per pixel
    [samples] = [axes for axes in figure.axes
                 if axes.get_title() == "samples per device (every pixel)"]
    assert samples.get_xlabel() == "sample"
    bars = [(box.x0, box.width) for collection in samples.collections
            for box in (path.get_extents() for path in collection.get_paths())]
    assert sorted(bars) == [(0, 12), (12, 4)]
    assert [axes.get_title() for axes in figure.axes].count("pieces over time") == 1
