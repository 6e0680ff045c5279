#!/usr/bin/env python3
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

    tools/genscene.py                      # the paper's scene, on stdout
    tools/genscene.py -o scenes/paper60.json
    tools/genscene.py --balls 600 --seed 7 --size 1024x1024 --depth 3
"""

import argparse
import sys

from rtcl_tools import files
from rtcl_tools.genscene import DEFAULT_SEED, REFERENCE_BALLS, PlacementError, build_scene, \
    to_json
from rtcl_tools.usage import parse_size


def main(argv=None):
    parser = argparse.ArgumentParser(
        description="Generate the 2009 paper's balls-on-a-table scene as rtcl-scene JSON.")
    parser.add_argument("--balls", type=int, default=REFERENCE_BALLS, metavar="N",
                        help="number of balls (default %(default)s)")
    parser.add_argument("--seed", type=int, default=DEFAULT_SEED, metavar="S",
                        help="random seed (default %(default)s)")
    parser.add_argument("--size", type=parse_size, default=(2000, 2000), metavar="WxH",
                        help="image size (default 2000x2000)")
    parser.add_argument("--depth", type=int, default=5, metavar="N",
                        help="max_depth, 0 ... 64 (default %(default)s)")
    parser.add_argument("-o", "--output", metavar="FILE",
                        help="write here instead of stdout")
    args = parser.parse_args(argv)
    if args.balls < 0:
        parser.error("--balls must be >= 0, got %d" % args.balls)
    if not 0 <= args.depth <= 64:
        parser.error("--depth must be 0 ... 64, got %d" % args.depth)

    try:
        text = to_json(build_scene(args.balls, args.seed, args.size, args.depth))
    except PlacementError as error:
        print("genscene: %s" % error, file=sys.stderr)
        return 1
    if args.output:
        files.write_text(args.output, text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
