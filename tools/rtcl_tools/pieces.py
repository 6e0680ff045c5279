"""The pieces of one image over several devices, from rtcl --stats: which device
rendered which pixel, and when.

`rtcl --devices LIST --stats FILE` records, under "multidevice", every piece of
the last frame ("pieces": its device, its rectangle of split rows x0, y0,
width, height, start_ms, end_ms and kernel_ms) and the row map that turns split
rows into image rows ("row_band", "row_bands", "row_classes"; docs/GUIDE.md,
"How the rows are ordered").  One process only: --mpi and --frames record no
pieces.
"""

import json
import pathlib

import numpy as np

from .files import open_input

NO_DEVICE = -1  # a pixel that no piece covered


class PiecesError(ValueError):
    """Stats that hold no pieces, or pieces that do not tile the image; the
    message names the file."""


def image_row(v, band, bands, classes):
    """Split row v's image row (rt_piece_row in cl/rtcl_shared.h): the image's
    whole bands of `band` rows dealt to `classes` classes, class after class,
    each top to bottom; band 0 or no classes: v itself."""
    if band <= 0 or classes <= 0 or v >= band * bands:
        return v
    b = v // band
    q, r = divmod(bands, classes)
    if b < r * (q + 1):
        c, k = divmod(b, q + 1)
    else:
        c, k = divmod(b - r * (q + 1), q)
        c += r
    return (c + k * classes) * band + v % band


def load_pieces(path):
    """Returns the --stats document at path, checked to hold an image's pieces;
    raises PiecesError naming what is wrong."""
    path = pathlib.Path(path)
    try:
        with open_input(path, "r") as stream:
            stats = json.loads(stream.read())
    except OSError as error:
        raise PiecesError(f"{path}: cannot read it ({error.strerror})") from None
    except (UnicodeDecodeError, json.JSONDecodeError):
        raise PiecesError(f"{path}: not rtcl --stats JSON") from None
    multidevice = stats.get("multidevice") if isinstance(stats, dict) else None
    if not isinstance(multidevice, dict) or not multidevice.get("pieces"):
        raise PiecesError(f"{path}: no pieces of an image; write them with rtcl --devices "
                          "LIST --stats FILE (one image in one process: --frames and --mpi "
                          "record none)")
    try:
        width, height = int(stats["width"]), int(stats["height"])
        for piece in multidevice["pieces"]:
            for key in ("device", "x0", "y0", "width", "height"):
                int(piece[key])
            for key in ("start_ms", "end_ms", "kernel_ms"):
                float(piece[key])
        for key in ("row_band", "row_bands", "row_classes"):
            int(multidevice.get(key, 0))
    except (KeyError, TypeError, ValueError):
        raise PiecesError(f"{path}: pieces without their image size, rectangle or times: "
                          "not rtcl --stats of --devices") from None
    if width < 1 or height < 1:
        raise PiecesError(f"{path}: an image of {width}x{height} pixels")
    return stats


def device_map(stats, source="the stats"):
    """Returns the (height, width) int array of the device that rendered each
    pixel (its index in multidevice.devices), NO_DEVICE where none did; raises
    PiecesError when a piece leaves the image or two pieces cover one pixel."""
    width, height = int(stats["width"]), int(stats["height"])
    md = stats["multidevice"]
    band, bands, classes = (int(md.get(key, 0)) for key in ("row_band", "row_bands",
                                                             "row_classes"))
    owner = np.full((height, width), NO_DEVICE, dtype=np.int64)
    for index, piece in enumerate(md["pieces"]):
        x0, y0 = int(piece["x0"]), int(piece["y0"])
        w, h = int(piece["width"]), int(piece["height"])
        if x0 < 0 or y0 < 0 or w < 1 or h < 1 or x0 + w > width or y0 + h > height:
            raise PiecesError(f"{source}: piece {index} ({w}x{h} at {x0}, {y0}) leaves the "
                              f"{width}x{height} image")
        for v in range(y0, y0 + h):
            row = owner[image_row(v, band, bands, classes), x0:x0 + w]
            if (row != NO_DEVICE).any():
                raise PiecesError(f"{source}: piece {index} covers pixels another piece "
                                  "covers")
            row[:] = int(piece["device"])
    return owner


def splits_samples(stats):
    """Whether the devices split the samples (rtcl --split samples): every
    piece is the whole image with a range of every pixel's samples."""
    return stats["multidevice"].get("split") == "samples"


def sample_ranges(stats, source="the stats"):
    """Under --split samples: (device, first sample, end) of each piece;
    raises PiecesError when a piece has no range of samples."""
    try:
        return [(int(piece["device"]), int(piece["samples"][0]), int(piece["samples"][1]))
                for piece in stats["multidevice"]["pieces"]]
    except (KeyError, IndexError, TypeError, ValueError):
        raise PiecesError(f"{source}: samples split without each piece's samples: "
                          "not rtcl --stats of --split samples") from None


def device_names(stats):
    """Each device's name as --stats gives it, by index."""
    return [str(device.get("device", f"device {k}"))
            for k, device in enumerate(stats["multidevice"].get("devices", []))]
