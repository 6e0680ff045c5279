"""Draw a render's work map and schedule map in one figure, each panel with its
colour bar and labelled axes.

Reads what one instrumented run of rtcl writes:

    rtcl -k dynamic --size 800x800 --work-map work.npy --schedule-map schedule.npy
    rtcl-maps --work work.npy --schedule schedule.npy -o maps.png

and draws, side by side, the image as rendered (row 0 at the top, axes in
pixels):

1. from --work (`rtcl --work-map FILE.npy`: dtype '<u8', shape (height, width)),
   the flops spent on each pixel, in the flop unit that shows the largest as 1 to
   999 (colour bar "flops per pixel (kFLOP)"); on a linear scale, or with --log a
   logarithmic one from the cheapest pixel that did any work, where a pixel of no
   work takes the lowest colour;
2. from --schedule (`rtcl --schedule-map FILE.npy`: dtype '<u4', shape (height,
   width, 3); docs/RENDERING.md, "The schedule map"), the work-group that traced
   each pixel (colour bar "work-group");
3. from the same file, the order in which the pixels were started: each pixel's
   ticket as a share of the started pixels, 0 the first and 1 the last (colour bar
   "order started (share of pixels)").

A pixel that no work-item started is grey in panels 2 and 3.

With --pieces (`rtcl --devices LIST --stats FILE`: one image over several
devices of one process; docs/GUIDE.md, "How the rows are ordered"), two more
panels show the schedule over the devices:

4. the device that rendered each pixel (colour bar "device", the index of
   multidevice.devices), its pieces placed through the row map, so that
   interleaved rows show as the bands each device took; under --split samples,
   where every device renders every pixel, each device's range of every
   pixel's samples instead (x: the sample);
5. each device's pieces over the frame's time (x: ms from the frame's start,
   y: the device, named on the axis), one bar per piece, from when the device
   took it to when it was done.

Give --work, --schedule, --pieces or any of them together; the maps and the
pieces must be of the same render (the same height x width).  A file that is missing, not a .npy or not such an array is an
error: one line on stderr, exit status 1, and no output file; so is an output
that is not .png, .svg or .pdf, or one tracked by git (unless --update-committed).
The figure is written to a temporary file and renamed.  Needs numpy and
matplotlib.
"""

import argparse
import pathlib

from ..requirements import require

require("numpy")  # the maps; matplotlib once the options are read (--help needs none)

import numpy as np  # noqa: E402

from .. import files  # noqa: E402
from ..flops import FLOPS_DTYPE, flop_unit, output_format, read_npy  # noqa: E402
from ..interrupts import interruptible  # noqa: E402
from ..pieces import (NO_DEVICE, PiecesError, device_map, device_names, load_pieces,  # noqa: E402
                      sample_ranges, splits_samples)
from ..plots import pyplot  # noqa: E402
from ..report import one_line  # noqa: E402
from ..schedule import ScheduleMapError, load_map, order_started, started  # noqa: E402
from ..usage import add_update_committed, program_name, report_error  # noqa: E402

UNSTARTED_COLOUR = "0.6"  # grey, on none of the colour maps' ends
WORK_LABEL = "flops per pixel"
GROUP_LABEL = "work-group"
ORDER_LABEL = "order started (share of pixels)"
DEVICE_LABEL = "device"
TIME_LABEL = "ms from the frame's start"
PANEL_WIDTH = 5.2  # inches, the colour bar included
PANEL_HEIGHT = 4.6


class WorkMapError(ValueError):
    """A work map that cannot be read; the message names the file."""


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description="Draw the work map (flops per pixel) and the schedule map (work-group "
                    "and order started per pixel) of a render in one figure, each with "
                    "its colour bar, from rtcl --work-map and --schedule-map .npy files.")
    parser.add_argument("--work", metavar="WORK.npy",
                        help="flops per pixel, written by rtcl --work-map FILE.npy")
    parser.add_argument("--schedule", metavar="SCHED.npy",
                        help="work-group, work-item and ticket per pixel, written by rtcl "
                             "--schedule-map FILE.npy")
    parser.add_argument("--pieces", metavar="STATS.json",
                        help="the pieces of one image over several devices, written by rtcl "
                             "--devices LIST --stats FILE: the device per pixel and each "
                             "device's pieces over time")
    parser.add_argument("-o", "--output", default="maps.png",
                        help="figure to write: .png, .svg or .pdf (default %(default)s)")
    parser.add_argument("--log", action="store_true",
                        help="a log colour scale for the work (pixels of no work take the "
                             "lowest colour)")
    parser.add_argument("--title", help="title over the whole figure")
    add_update_committed(parser)
    arguments = parser.parse_args(argv)
    if arguments.work is None and arguments.schedule is None and arguments.pieces is None:
        parser.error("give --work WORK.npy, --schedule SCHED.npy, --pieces STATS.json or "
                     "several")
    return arguments


def load_work_map(path):
    """Returns the (height, width) uint64 flops per pixel of the work map at path;
    raises WorkMapError naming what is wrong."""
    path = pathlib.Path(path)
    work = read_npy(path, WorkMapError)
    if work.dtype != FLOPS_DTYPE or work.ndim != 2 or work.size == 0:
        raise WorkMapError(f"{path}: not a work map (dtype {work.dtype}, shape {work.shape}; "
                           "rtcl --work-map FILE.npy writes uint64, height x width)")
    return work


def check_same_render(first_name, first_shape, second_name, second_shape):
    """Raises ValueError when two inputs are not of one image size ((height,
    width) each)."""
    if tuple(first_shape) != tuple(second_shape):
        raise ValueError(f"{first_name} is {first_shape[0]}x{first_shape[1]} (height x "
                         f"width) but {second_name} is {second_shape[0]}x{second_shape[1]}: "
                         "give the maps of one render")


def panel_count(work, schedule, pieces=None):
    return (work is not None) + 2 * (schedule is not None) + 2 * (pieces is not None)


def draw_maps(figure, work=None, schedule=None, *, pieces=None, log=False, title=None):
    """Draws the panels of work (flops per pixel), schedule (a schedule map) and
    pieces (a --stats document of --devices) onto figure, side by side."""
    count = panel_count(work, schedule, pieces)
    axes = list(np.atleast_1d(figure.subplots(1, count)))
    if work is not None:
        _draw_work(figure, axes.pop(0), work, log)
    if schedule is not None:
        _draw_groups(figure, axes.pop(0), schedule)
        _draw_order(figure, axes.pop(0), schedule)
    if pieces is not None:
        if splits_samples(pieces):
            _draw_samples(axes.pop(0), pieces)
        else:
            _draw_devices(figure, axes.pop(0), pieces)
        _draw_timeline(axes.pop(0), pieces)
    if title:
        figure.suptitle(title)


def _colour_map(name):
    from matplotlib import colormaps
    colours = colormaps[name].copy()
    colours.set_bad(UNSTARTED_COLOUR)
    return colours


def _image(figure, axes, values, heading, label, ticks=None, **style):
    """Shows values (row 0 at the top) on axes with a colour bar labelled label."""
    picture = axes.imshow(values, origin="upper", **style)
    axes.set_title(heading)
    axes.set_xlabel("pixel x")
    axes.set_ylabel("pixel y")
    figure.colorbar(picture, ax=axes, label=label, ticks=ticks)


def _draw_work(figure, axes, work, log):
    from matplotlib.colors import LogNorm, Normalize
    largest = int(work.max())
    divisor, unit = flop_unit(largest)
    values = work.astype(np.float64) / divisor
    if log:
        positive = values[values > 0]
        low = positive.min() if positive.size else 1 / divisor
        high = values.max() if values.max() > low else 10 * low
        norm = LogNorm(vmin=low, vmax=high)
        values = np.maximum(values, low)  # no work: the lowest colour
        label = f"{WORK_LABEL} ({unit}, log scale)"
    else:
        norm = Normalize(vmin=0, vmax=values.max() if largest else 1)
        label = f"{WORK_LABEL} ({unit})"
    _image(figure, axes, values, "work per pixel", label, cmap="viridis", norm=norm)


def _draw_groups(figure, axes, schedule):
    from matplotlib.ticker import MaxNLocator
    groups = np.ma.masked_where(~started(schedule), schedule[..., 0].astype(np.float64))
    top = int(groups.max()) if groups.count() else 0
    # nearest: resampling between two groups' numbers would show a third group.
    _image(figure, axes, groups, "work-group per pixel", GROUP_LABEL,
           ticks=MaxNLocator(integer=True), cmap=_colour_map("turbo"), vmin=0,
           vmax=max(top, 1), interpolation="nearest")


def _draw_order(figure, axes, schedule):
    order = np.ma.masked_invalid(order_started(schedule))
    _image(figure, axes, order, "order pixels were started", ORDER_LABEL,
           cmap=_colour_map("plasma"), vmin=0, vmax=1)


def _device_colours(count):
    """One colour per device, the timeline's: tab10's, repeated past ten."""
    from matplotlib import colormaps
    from matplotlib.colors import ListedColormap
    colours = ListedColormap([colormaps["tab10"](k % 10) for k in range(count)])
    colours.set_bad(UNSTARTED_COLOUR)
    return colours


def _draw_devices(figure, axes, stats):
    owner = device_map(stats)
    devices = np.ma.masked_where(owner == NO_DEVICE, owner.astype(np.float64))
    count = max(len(device_names(stats)), int(owner.max()) + 1, 1)
    # nearest: resampling between two devices' numbers would show a third.
    _image(figure, axes, devices, "device per pixel", DEVICE_LABEL, ticks=range(count),
           cmap=_device_colours(count), vmin=-0.5, vmax=count - 0.5,
           interpolation="nearest")


def _device_rows(axes, names, count):
    """One row per device, top to bottom, named on the y axis."""
    axes.set_yticks(range(count))
    axes.set_yticklabels([f"{k}: {names[k][:28]}" if k < len(names) else str(k)
                          for k in range(count)])
    axes.set_ylim(count - 0.5, -0.5)


def _draw_samples(axes, stats):
    """--split samples: every device rendered every pixel, so instead of a
    device per pixel, each device's range of every pixel's samples."""
    names = device_names(stats)
    ranges = sample_ranges(stats)
    count = max(len(names), max(k for k, _, _ in ranges) + 1)
    colours = _device_colours(count)
    for k, first, end in ranges:
        axes.broken_barh([(first, end - first)], (k - 0.4, 0.8), facecolors=colours(k),
                         edgecolors="black", linewidth=0.5)
    _device_rows(axes, names, count)
    axes.set_xlabel("sample")
    axes.set_title("samples per device (every pixel)")


def _draw_timeline(axes, stats):
    pieces = stats["multidevice"]["pieces"]
    names = device_names(stats)
    count = max(len(names), max(int(p["device"]) for p in pieces) + 1)
    colours = _device_colours(count)
    for piece in pieces:
        k = int(piece["device"])
        start, end = float(piece["start_ms"]), float(piece["end_ms"])
        axes.broken_barh([(start, max(end - start, 0.0))], (k - 0.4, 0.8),
                         facecolors=colours(k), edgecolors="black", linewidth=0.5)
    _device_rows(axes, names, count)
    axes.set_xlabel(TIME_LABEL)
    axes.set_title("pieces over time")


def plot_maps(out_path, work=None, schedule=None, *, pieces=None, log=False, title=None):
    """Draws the maps into one figure and writes it to out_path (png, svg or pdf)."""
    file_format = output_format(out_path)
    plt = pyplot()
    count = panel_count(work, schedule, pieces)
    figure = plt.figure(figsize=(PANEL_WIDTH * count, PANEL_HEIGHT), layout="constrained")
    try:
        draw_maps(figure, work, schedule, pieces=pieces, log=log, title=title)
        files.save_figure(figure, out_path, file_format)
    finally:
        plt.close(figure)


def draw(arguments):
    """Reads the maps and writes the figure."""
    output_format(arguments.output)
    files.reading([arguments.work, arguments.schedule, arguments.pieces])
    files.check_outputs([arguments.output])
    work = load_work_map(arguments.work) if arguments.work else None
    schedule = load_map(arguments.schedule) if arguments.schedule else None
    pieces = load_pieces(arguments.pieces) if arguments.pieces else None
    shapes = [(f"the work map {arguments.work}", work.shape) if work is not None else None,
              (f"the schedule map {arguments.schedule}", schedule.shape[:2])
              if schedule is not None else None,
              (f"the pieces of {arguments.pieces}", (int(pieces["height"]), int(pieces["width"])))
              if pieces is not None else None]
    shapes = [shape for shape in shapes if shape]
    for other in shapes[1:]:
        check_same_render(*shapes[0], *other)
    if pieces is not None and splits_samples(pieces):
        sample_ranges(pieces, arguments.pieces)  # pieces without their samples: refused
    elif pieces is not None:
        device_map(pieces, arguments.pieces)  # pieces that do not tile the image: refused
    plot_maps(arguments.output, work, schedule, pieces=pieces, log=arguments.log,
              title=arguments.title)


@interruptible
def main(argv=None):
    arguments = parse_arguments(argv)
    program = program_name()
    require("matplotlib")
    try:
        with files.committed_files_allowed(arguments.update_committed):
            draw(arguments)
    except (WorkMapError, ScheduleMapError, PiecesError, ValueError, OSError) as error:
        return report_error(program, one_line(error))
    return 0
