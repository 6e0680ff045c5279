"""Generate the 2009 paper's experiment scene as an rtcl scene file (SCENE.md).

The scene of "Ray Tracing in CUDA" (2009): N balls (default 60) with random
colours resting on a checkered support table (the plane y = 0), lit by two point
lights, rendered at 2000x2000.  About 60 % of the balls are diffuse, 25 % mirror-like
and 15 % glass (exact counts, shuffled over the balls).

Layout: the camera looks down on the table at about 15 degrees; the balls are
placed by rejection sampling (uniform over the table, radius uniform in
[R_MIN, R_MAX], no two balls closer than GAP) inside the part of the table that the
camera frames, so that every ball lies wholly inside the picture and the cluster
fills the frame below the horizon, with background above it.  Every length of the
layout except the ball radii grows with sqrt(N / 60), so a larger N keeps the same
density and framing, only with smaller-looking balls.  The layout is computed for
a square picture and does not depend on --size (a wider picture shows more table).

The output depends only on the options: the same --seed gives the same bytes.

    rtcl-genscene                          # the paper's scene, on stdout
    rtcl-genscene --balls 600 --seed 7 --size 1024x1024 --depth 3 -o balls600.json
    tools/genscene.py -o scenes/paper60.json --update-committed   # the committed scene

A file tracked by git (scenes/paper60.json) is replaced only with --update-committed.
--balls is at most a million (about 2 minutes and a 175 MB file here; 10^8 would
take hours).
"""

import argparse
import sys

from .. import files
from ..genscene import DEFAULT_SEED, REFERENCE_BALLS, PlacementError, build_scene, to_json
from ..interrupts import interruptible
from ..usage import (add_update_committed, os_error_message, parse_size, program_name,
                     report_error)

# Placement takes about 0.1 ms a ball here (10^5 balls: 10 s, 17.5 MB of JSON).
MAX_BALLS = 1_000_000


@interruptible
def main(argv=None):
    parser = argparse.ArgumentParser(
        description="Generate the 2009 paper's balls-on-a-table scene as rtcl-scene JSON.")
    parser.add_argument("--balls", type=int, default=REFERENCE_BALLS, metavar="N",
                        help=f"number of balls, 0 ... {MAX_BALLS} (default %(default)s)")
    parser.add_argument("--seed", type=int, default=DEFAULT_SEED, metavar="S",
                        help="random seed (default %(default)s)")
    parser.add_argument("--size", type=parse_size, default=(2000, 2000), metavar="WxH",
                        help="image size (default 2000x2000)")
    parser.add_argument("--depth", type=int, default=5, metavar="N",
                        help="max_depth, 0 ... 64 (default %(default)s)")
    parser.add_argument("-o", "--output", "--out", metavar="FILE",
                        help="write here instead of stdout")
    add_update_committed(parser)
    args = parser.parse_args(argv)
    if not 0 <= args.balls <= MAX_BALLS:
        parser.error(f"--balls must be 0 ... {MAX_BALLS}, got {args.balls} (a million balls "
                     "take about 2 minutes here and a 175 MB scene file)")
    if not 0 <= args.depth <= 64:
        parser.error("--depth must be 0 ... 64, got %d" % args.depth)

    try:
        if args.output:   # refused before the placement, not after
            with files.committed_files_allowed(args.update_committed):
                files.check_outputs([args.output])
        text = to_json(build_scene(args.balls, args.seed, args.size, args.depth))
    except PlacementError as error:
        return report_error(program_name(), error)
    except OSError as error:
        return report_error(program_name(), os_error_message(error))
    if args.output:
        try:
            with files.committed_files_allowed(args.update_committed):
                files.write_text(args.output, text)
        except OSError as error:
            return report_error(program_name(), os_error_message(error))
    else:
        sys.stdout.write(text)
    return 0

