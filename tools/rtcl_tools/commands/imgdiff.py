"""Compare images with a reference, pixel by pixel, ignoring headers and metadata
(rtcl's name the kernel that rendered them).

    rtcl-imgdiff REFERENCE FILE...  [--threshold T]

Reads every format rtcl writes: PPM, PFM and PNG itself, others (EXR, HDR, TIFF,
...) through OpenImageIO's iinfo (their sizes, compared first: idiff compares
images of different sizes over their common part) and idiff, when installed.  A
folder, FIFO or device is refused at once, never read.  Prints, per file, how many
channel values differ from the reference, the largest absolute difference (on a
0 ... 1 scale: 1/255 is one 8-bit level; also in levels for 8-bit images) and the
PSNR; with --threshold, pass or FAIL.

Exit status: 0 when every file has the reference's size and (with --threshold)
no difference above T; 1 when one does not; 2 when a file cannot be read.
rtcl-ppmdiff is the same command under its old name.
"""

import argparse
import math
import sys

from ..files import open_input
from ..images import (ImageError, SizeDiffers, compare, compare_with_idiff, native_format,
                      read)
from ..interrupts import interruptible
from ..usage import program_name


def threshold(text):
    """Returns T from '0.004' or from a fraction such as '1/255'."""
    try:
        numerator, _, denominator = text.partition("/")
        value = float(numerator) / (float(denominator) if denominator else 1.0)
    except (ValueError, ZeroDivisionError):
        raise argparse.ArgumentTypeError(f"expected a number such as 0.004 or 1/255, "
                                         f"got {text!r}") from None
    if not value >= 0 or not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description="Compare images (PPM, PFM, PNG; EXR, HDR, TIFF, ... through "
                    "OpenImageIO's idiff) with a reference: values that differ, largest "
                    "absolute difference, PSNR.",
        epilog="Exit status: 0 same size (and within --threshold), 1 a size differs or a "
               "difference exceeds --threshold, 2 a file cannot be read.")
    parser.add_argument("reference", metavar="REFERENCE")
    parser.add_argument("files", nargs="+", metavar="FILE")
    parser.add_argument("-t", "--threshold", type=threshold, metavar="T",
                        help="fail when a channel value differs by more than T (on the "
                             "0 ... 1 scale; 1/255 is one 8-bit level)")
    return parser.parse_args(argv)


def file_kind(path):
    """Returns 'ppm', 'pfm' or 'png' when the file is one of those, else None."""
    try:
        with open_input(path) as stream:
            return native_format(stream.read(8))
    except OSError as error:
        raise ImageError(f"{path}: cannot read: {error.strerror}") from None


def describe(path, reference_path, result, limit):
    """Returns the report line of one file, and whether it passes."""
    if result.differing == 0:
        text = f"{path}: same pixels as {reference_path}"
    else:
        levels = f" (max {result.max_levels}/255)" if result.max_levels is not None else ""
        text = (f"{path}: {result.differing} {result.unit} differ{levels} from "
                f"{reference_path}; max abs diff {result.max_abs:.6g}, PSNR "
                f"{result.psnr:.2f} dB")
    if limit is None:
        return text, True
    passed = result.max_abs <= limit
    return text + (f"; pass (threshold {limit:g})" if passed
                   else f"; FAIL (above threshold {limit:g})"), passed


def compare_files(reference_path, reference, path, limit):
    """Returns (report line, passes) for one file against the reference."""
    if reference is None or file_kind(path) is None:
        shape = (reference.width, reference.height, reference.channels) if reference else None
        try:
            result = compare_with_idiff(reference_path, path, limit, shape)
        except SizeDiffers as differs:
            return str(differs), False
        return describe(path, reference_path, result, limit)
    image = read(path)
    if (image.width, image.height, image.channels) != \
            (reference.width, reference.height, reference.channels):
        return (f"{path}: size {image.width}x{image.height} ({image.channels} channels) "
                f"differs from {reference.width}x{reference.height} ({reference.channels} "
                f"channels) of {reference_path}"), False
    return describe(path, reference_path, compare(reference, image), limit)


@interruptible
def main(argv=None):
    arguments = parse_arguments(argv)
    program = program_name()
    try:
        reference = read(arguments.reference) if file_kind(arguments.reference) else None
        status = 0
        for path in arguments.files:
            line, passed = compare_files(arguments.reference, reference, path,
                                         arguments.threshold)
            print(line)
            status = status or (0 if passed else 1)
    except ImageError as error:
        print(f"{program}: error: {error}", file=sys.stderr)
        return 2
    return status
