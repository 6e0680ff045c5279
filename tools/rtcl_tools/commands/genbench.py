"""Generate the benchmark scenes (issue 11 item 7) as rtcl scene files in a folder.

Nothing large is committed: every scene is made here, deterministically (the same
options give the same bytes), in seconds.  Scenes:

  balls         Eric Haines' SPD sphereflake: sum of 9^k, k = 0 ... size, mirrored
                spheres (10, 91, 820, 7381, 66430 at size 1 ... 5) over a floor.
                Version 1: today's rtcl renders it.
  tetra         SPD recursive tetrahedron: 4^size triangles (4096 at size 6).
  mount         SPD fractal mountain, 2 * 4^size triangles (8192 at size 6), with
                its pyramid of 4 glass spheres.
  lake          mount at size 10 (2,097,152 triangles) plus a mirror lake: the
                million-triangle scene with glass and mirror.
  lake-path     the lake path-traced (issue 41): glass, a diffuse mountain, a
                tinted mirror lake (two triangles), the sun and the sky; 16
                samples, depth 8.
  random-balls  the 2009 paper's balls on a table (tools/genscene.py) at 60, 200,
                400, 2000 and 20,000 balls (or --balls N,...).  Version 1.
  assimp        models of Debian's assimp-testmodels (Wuson as PLY, OBJ and STL, a
                binary STL spider) in glass, mirror and red, referenced by path.
  all           the set `make bench-scenes` writes (docs/benchmark-scenes.md).

Triangle scenes are version 2 (docs/SCENE.md): up to 4096 triangles inline in the
JSON ("triangles"), more in a binary PLY beside it ("meshes"); --triangles
inline|ply chooses.  Each SPD keeps its own camera (z up), lights and colours,
at its 512x512 unless --image says otherwise.

    rtcl-genbench balls --size 3 -o build/bench-scenes
    rtcl-genbench mount --size 8 -o build/bench-scenes
    rtcl-genbench random-balls --balls 60,2000 -o build/bench-scenes
    rtcl-genbench all -o build/bench-scenes
(tools/genbench.py in a checkout is the same command.)  A file tracked by git in
the folder is never replaced.
"""

import argparse
import os

from ..requirements import require

require("numpy")  # the meshes

from .. import benchscenes, files, spd  # noqa: E402
from ..interrupts import interruptible  # noqa: E402
from ..report import one_line  # noqa: E402
from ..usage import parse_size, program_name, report_error  # noqa: E402

# Database: (default size, largest size, what the size counts).
SIZES = {"balls": (4, 6, "levels: sum of 9^k spheres, k = 0 ... size"),
         "tetra": (6, 11, "4^size triangles"),
         "mount": (6, 11, "2 * 4^size triangles"),
         "lake": (10, 11, "2 * 4^size triangles"),
         "lake-path": (10, 11, "2 * 4^size triangles")}


def size_type(name):
    low, high = 1, SIZES[name][1]

    def parse(text):
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError("expected an integer, got %r" % text) from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError("must be %d ... %d for %s, got %d"
                                             % (low, high, name, value))
        return value
    return parse


def ball_counts(text):
    try:
        counts = tuple(int(part) for part in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError("expected N or N,N,..., got %r" % text) from None
    if any(n < 0 for n in counts):
        raise argparse.ArgumentTypeError("ball counts must be >= 0, got %r" % text)
    return counts


def depth_type(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError("expected an integer, got %r" % text) from None
    if not 0 <= value <= 64:
        raise argparse.ArgumentTypeError("must be 0 ... 64, got %d" % value)
    return value


def add_common(sub, image_default, depth_default=5):
    sub.add_argument("-o", "--out", "--output-dir", dest="output_dir", required=True,
                     metavar="DIR",
                     help="folder to write into (made if missing)")
    if image_default is not None:
        sub.add_argument("--image", type=parse_size, default=image_default, metavar="WxH",
                         help="image size (default %dx%d)" % image_default)
        sub.add_argument("--depth", type=depth_type, default=depth_default, metavar="N",
                         help="max_depth, 0 ... 64 (default %d)" % depth_default)


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0],
        epilog=__doc__.split("\n\n", 1)[1], formatter_class=argparse.RawDescriptionHelpFormatter)
    subs = parser.add_subparsers(dest="database", required=True, metavar="SCENE")
    for name, (default, high, counts) in SIZES.items():
        sub = subs.add_parser(name, help="SPD %s (--size 1 ... %d, default %d: %s)"
                              % (name, high, default, counts) if not name.startswith("lake")
                              else "mount at --size (default 10) with a mirror lake"
                              + (", path-traced" if name == "lake-path" else ""))
        sub.add_argument("--size", type=size_type(name), default=default, metavar="N",
                         help="size factor 1 ... %d (default %d): %s" % (high, default, counts))
        if name in ("tetra", "mount"):
            sub.add_argument("--triangles", choices=("auto", "inline", "ply"), default="auto",
                             help="inline in the JSON, or a PLY file beside it (default "
                                  "auto: inline up to %d triangles)" % spd.INLINE_LIMIT)
        add_common(sub, spd.SPD_IMAGE, 8 if name == "lake-path" else 5)
    sub = subs.add_parser("random-balls", help="the 2009 paper's balls on a table")
    sub.add_argument("--balls", type=ball_counts, default=benchscenes.RANDOM_BALL_SERIES,
                     metavar="N,...", help="ball counts (default 60,200,400,2000,20000)")
    sub.add_argument("--seed", type=int, default=benchscenes.genscene.DEFAULT_SEED,
                     metavar="S", help="random seed (default %(default)s)")
    add_common(sub, (2000, 2000))
    for name, text in (("assimp", "models of assimp-testmodels in glass, mirror and red"),
                       ("all", "the whole set of make bench-scenes")):
        sub = subs.add_parser(name, help=text)
        sub.add_argument("--models", default=benchscenes.ASSIMP_MODELS, metavar="DIR",
                         help="assimp-testmodels' models folder (default %(default)s)")
        add_common(sub, (800, 600) if name == "assimp" else None)
    return parser.parse_args(argv)


def benches(args):
    """Yields the Bench objects the arguments ask for."""
    db = args.database
    if db == "balls":
        yield spd.balls(args.size, args.image, args.depth)
    elif db in ("tetra", "mount"):
        yield getattr(spd, db)(args.size, args.image, args.depth, args.triangles)
    elif db == "lake":
        yield spd.lake(args.size, args.image, args.depth)
    elif db == "lake-path":
        yield spd.lake_path(args.size, args.image, args.depth)
    elif db == "random-balls":
        for n in args.balls:
            yield benchscenes.random_balls(n, args.seed, args.image, args.depth)
    elif db == "assimp":
        yield benchscenes.assimp_models(args.models, args.image, args.depth)
    else:
        yield from benchscenes.standard_set(args.models)


def summary(bench):
    scene = bench.scene
    singular = {"spheres": "sphere", "planes": "plane", "triangles": "triangle", "meshes": "mesh"}
    parts = ["%d %s" % (len(scene[key]), key if len(scene[key]) > 1 else singular[key])
             for key in ("spheres", "planes", "triangles", "meshes") if scene.get(key)]
    parts += ["%s: %d triangles" % (name, len(faces))
              for name, (_, faces) in bench.meshes.items()]
    return ", ".join(parts)


@interruptible
def main(argv=None):
    args = parse_arguments(argv)
    try:
        files.check_output_folder(args.output_dir, [])
        os.makedirs(args.output_dir, exist_ok=True)
        for bench in benches(args):
            path = benchscenes.write(bench, args.output_dir)
            print("%s: %s" % (path, summary(bench)))
    except (OSError, benchscenes.genscene.PlacementError) as error:
        return report_error(program_name(), one_line(error))
    return 0

