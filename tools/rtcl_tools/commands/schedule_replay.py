"""Replay renders as an animation: the image filling up in the order its pixels
were started, each pixel in the colour of the work-group that traced it.

Reads the schedule maps that `rtcl --schedule-map FILE.npy` writes (dtype
'<u4', shape (height, width, 3): work-group, work-item in the group, ticket;
docs/RENDERING.md, "The schedule map") and writes an animated GIF with one
panel per map, side by side and labelled: frame k shows every pixel whose
ticket is below k/N of the pixels. Put several kernels' maps next to each other
to see cyclic's interleaved groups against dynamic's fetches:

    rtcl -k cyclic -w 16x16 --groups 4x2 --size 320x240 --schedule-map cyclic.npy
    rtcl -k dynamic -w 16x16 --groups 4x2 --size 320x240 --schedule-map dynamic.npy
    rtcl-schedule-replay cyclic.npy dynamic.npy -o replay.gif

The colours are rtcl's own (the same hash of the group number as its
--schedule-map picture). A file that is missing, unreadable or not such an
array is an error: one line on stderr, exit status 1, and no output file; so is
an output file tracked by git (unless --update-committed). Needs numpy and
Pillow (which matplotlib brings).
"""

import argparse
import pathlib

from ..requirements import require

require("numpy")

import numpy as np  # noqa: E402

from .. import files  # noqa: E402
from ..interrupts import interruptible  # noqa: E402
from ..report import one_line  # noqa: E402
from ..schedule import UNSTARTED_GROUP, ScheduleMapError, load_map  # noqa: E402
from ..usage import add_update_committed, program_name, report_error  # noqa: E402

LABEL_HEIGHT = 16
GAP = 8
UNSTARTED = (40, 40, 40)
MIN_BRIGHTEST = 0.45  # output/schedmap.h, SCHEDMAP_MIN_BRIGHTEST


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description="Replay renders as an animated GIF: pixels appear in the order they "
                    "were started, coloured by work-group, from rtcl --schedule-map files.")
    parser.add_argument("maps", nargs="+", metavar="MAP.npy",
                        help="schedule maps written by rtcl --schedule-map FILE.npy")
    parser.add_argument("-o", "--output", default="replay.gif",
                        help="the animation to write, a .gif (default %(default)s)")
    parser.add_argument("--frames", type=int, default=48,
                        help="frames of the animation (default %(default)s)")
    parser.add_argument("--fps", type=float, default=12,
                        help="frames per second (default %(default)s)")
    parser.add_argument("--labels", help="comma-separated panel labels (default: the file "
                                         "names without .npy)")
    add_update_committed(parser)
    arguments = parser.parse_args(argv)
    if arguments.frames < 1:
        parser.error("--frames must be at least 1")
    if arguments.fps <= 0:
        parser.error("--fps must be above 0")
    if pathlib.Path(arguments.output).suffix.lower() != ".gif":
        parser.error(f"-o/--output: {arguments.output}: write a .gif (the one format this "
                     "tool writes; ffmpeg turns a GIF into an MP4)")
    labels = arguments.labels.split(",") if arguments.labels else None
    if labels is not None and len(labels) != len(arguments.maps):
        parser.error(f"--labels names {len(labels)} panels for {len(arguments.maps)} maps")
    arguments.labels = labels
    return arguments


def group_colours(groups):
    """rtcl's colour of each work-group (output/schedmap.c): a lowbias32 hash of
    the number, each channel 0.15 + 0.8 of one byte of it, a colour whose
    brightest channel is below MIN_BRIGHTEST lifted by the difference (so that
    no group is near UNSTARTED's grey); 8-bit, unencoded."""
    h = groups.astype(np.uint32)
    with np.errstate(over="ignore"):
        h = h ^ (h >> 16)
        h = (h * np.uint32(0x7FEB352D)).astype(np.uint32)
        h = h ^ (h >> 15)
        h = (h * np.uint32(0x846CA68B)).astype(np.uint32)
        h = h ^ (h >> 16)
    rgb = np.stack([(h >> (8 * c)) & 0xFF for c in range(3)], axis=-1).astype(np.float64)
    rgb = 0.15 + 0.8 * rgb / 255.0
    brightest = rgb.max(axis=-1, keepdims=True)
    rgb = np.where(brightest < MIN_BRIGHTEST, rgb + (MIN_BRIGHTEST - brightest), rgb)
    rgb[groups == UNSTARTED_GROUP] = 0.0
    return np.clip(np.rint(rgb * 255), 0, 255).astype(np.uint8)


def frames_of(maps, labels, count):
    """The animation's frames as PIL images: the maps side by side under their
    labels, frame k showing the pixels whose ticket is below k/count of them."""
    from PIL import Image, ImageDraw

    height = max(m.shape[0] for m in maps) + LABEL_HEIGHT
    width = sum(m.shape[1] for m in maps) + GAP * (len(maps) - 1)
    colours = [group_colours(m[..., 0]) for m in maps]
    tickets = [m[..., 2].astype(np.int64) for m in maps]
    background = Image.new("RGB", (width, height), (0, 0, 0))
    draw = ImageDraw.Draw(background)
    x = 0
    for m, label in zip(maps, labels):
        draw.text((x + 2, 2), label, fill=(230, 230, 230))
        x += m.shape[1] + GAP
    frames = []
    for k in range(1, count + 1):
        frame = background.copy()
        x = 0
        for m, colour, ticket in zip(maps, colours, tickets):
            shown = ticket < k * m.shape[0] * m.shape[1] / count
            panel = np.where(shown[..., None], colour, np.array(UNSTARTED, np.uint8))
            frame.paste(Image.fromarray(panel.astype(np.uint8), "RGB"), (x, LABEL_HEIGHT))
            x += m.shape[1] + GAP
        frames.append(frame)
    return frames


def replay(arguments):
    maps = [load_map(path) for path in arguments.maps]
    labels = arguments.labels or [pathlib.Path(p).name.removesuffix(".npy")
                                  for p in arguments.maps]
    frames = frames_of(maps, labels, arguments.frames)
    duration = max(1, round(1000 / arguments.fps))
    with files.atomic_output(arguments.output, "wb") as stream:
        # The last frame, the whole schedule, stays a second longer.
        frames[0].save(stream, format="GIF", save_all=True, append_images=frames[1:],
                       duration=[duration] * (len(frames) - 1) + [duration + 1000], loop=0)


@interruptible
def main(argv=None):
    arguments = parse_arguments(argv)
    program = program_name()
    require("PIL")
    try:
        with files.committed_files_allowed(arguments.update_committed):
            files.reading(arguments.maps)
            files.check_outputs([arguments.output])
            replay(arguments)
    except (ScheduleMapError, OSError) as error:
        return report_error(program, one_line(error))
    return 0
