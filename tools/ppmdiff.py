#!/usr/bin/env python3
"""Compares the pixels of binary PPM files with a reference, ignoring headers
(rtcl's name the kernel that rendered them).

Usage: ppmdiff.py REFERENCE.ppm FILE.ppm...   (or -h, --help: this text)
Prints, per file, how many channel values differ from the reference and by
how much at most; exits 1 if any file's size differs from the reference's.
"""
import sys

from rtcl_tools.ppm import differences, pixels


def main(argv):
    if len(argv) == 2 and argv[1] in ("-h", "--help"):
        print(__doc__.strip())
        return 0
    if len(argv) < 3:
        sys.exit(__doc__.strip())
    size, reference = pixels(argv[1])
    status = 0
    for path in argv[2:]:
        other_size, other = pixels(path)
        if other_size != size:
            print(f"{path}: size {other_size} differs from {size}")
            status = 1
            continue
        count, largest = differences(reference, other)
        verdict = "same pixels as" if count == 0 else f"{count} values differ (max {largest}/255) from"
        print(f"{path}: {verdict} {argv[1]}")
    return status


if __name__ == "__main__":
    sys.exit(main(sys.argv))
