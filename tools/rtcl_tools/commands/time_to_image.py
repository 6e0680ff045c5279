"""Whole-process time to image: rtcl against POV-Ray 3.7 on one scene.

Issue 12's target: on a 60-ball scene not used for tuning (by default
genscene's seed 7; scenes/paper60.json is seed 2009), at 1000x1000 on this
machine's PoCL, rtcl's whole-process wall time to a PNG must be at most half
of POV-Ray 3.7's with +WT2.

    rtcl-time-to-image                          # 5 runs each, report on stdout
    rtcl-time-to-image -r 9 -o pocl.txt          # also into pocl.txt
    rtcl-time-to-image -s scenes/paper60.json --size 2000x2000
    tools/time_to_image.py -r 9 -o docs/results/time-to-image/pocl.txt --update-committed
(tools/time_to_image.py in a checkout is the same command; -o never replaces a
file tracked by git without --update-committed.)

Each run is one whole process, timed from start to exit on the wall clock:

    rtcl -s SCENE --size WxH --encoding linear -o render.png -q
    povray +Iscene.pov +Orender.png +WW +HH -A +WT2 -D +FN File_Gamma=1.0

(rtcl's plain render: default device and kernel, one launch; --encoding linear
writes round(255 c) as POV-Ray's File_Gamma 1.0 does; the SDL is
tools/povray.py's). The two alternate, round by round, so that a busy spell of
the machine falls on both; the report gives the median, min and max of each,
the ratio of the medians, the median CPU time (user + system over all threads,
which a busy machine hardly changes; the wall time it does), the load average before and after, the device (rtcl
-v) and the CPU (lscpu), and the median of rtcl's own -v time breakdown over
--runs more rtcl -v runs (untimed here: where rtcl's time goes). rtcl's
program cache (RTCL_CACHE, ~/.cache/rtcl) and PoCL's are left as they are:
the first, untimed, warm-up run of each fills them, as a user's first render
would.
"""

import argparse
import os
import shutil
import sys
import tempfile
from statistics import median

from ..requirements import require

require("numpy")  # the meshes of a version 2 scene

from .. import files, genscene, locations  # noqa: E402
from ..interrupts import interruptible  # noqa: E402
from ..povray_run import povray_version  # noqa: E402
from ..povray_sdl import to_sdl  # noqa: E402
from ..scene import SceneError, load_scene  # noqa: E402
from ..time_to_image import (RunError, cpu_model, format_breakdown, interleaved,  # noqa: E402
                             median_breakdown, parse_breakdown, povray_command,
                             ratio_verdict, rtcl_command, rtcl_device, summary, time_once)
from ..usage import (add_rtcl_option, add_update_committed, os_error_message,  # noqa: E402
                     parse_size, program_name)

TARGET = 0.5
BALLS = 60


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description="Whole-process time to image of rtcl and POV-Ray 3.7 on one scene.")
    parser.add_argument("-s", "--scene", metavar="FILE",
                        help="rtcl scene (default: genscene's 60 balls at --seed)")
    parser.add_argument("--seed", type=int, default=7, metavar="S",
                        help="genscene seed of the default scene (default %(default)s; "
                        "paper60 is 2009)")
    parser.add_argument("--size", type=parse_size, default=(1000, 1000), metavar="WxH",
                        help="image size (default 1000x1000)")
    parser.add_argument("-r", "--repeat", "--runs", dest="runs", type=int, default=5,
                        metavar="N",
                        help="timed runs of each program (default %(default)s)")
    parser.add_argument("--threads", type=int, default=2, metavar="N",
                        help="POV-Ray render threads, +WT (default %(default)s)")
    add_rtcl_option(parser)
    parser.add_argument("--povray", default="povray", metavar="EXE",
                        help="POV-Ray executable (default %(default)s)")
    parser.add_argument("-o", "--output", "--out", metavar="FILE",
                        help="also write the report to FILE")
    add_update_committed(parser)
    args = parser.parse_args(argv)
    if args.runs < 1:
        parser.error("--runs must be >= 1, got %d" % args.runs)
    if args.threads < 1:
        parser.error("--threads must be >= 1, got %d" % args.threads)
    return args


def scene_file(args, folder):
    """The scene's path and how the report names it."""
    if args.scene:
        load_scene(args.scene)  # a bad scene fails here, with its own message
        return os.path.abspath(args.scene), args.scene
    scene = genscene.build_scene(BALLS, args.seed, args.size, 5)
    path = os.path.join(folder, "scene.json")
    with open(path, "w", encoding="utf-8") as f:
        f.write(genscene.to_json(scene))
    return path, "tools/genscene.py --balls %d --seed %d --size %dx%d --depth 5" % (
        BALLS, args.seed, args.size[0], args.size[1])


def measure(args, rtcl, povray, folder, scene):
    """Warm-up, the interleaved timed runs and the -v runs: (walls, breakdowns)."""
    rtcl_dir, pov_dir = os.path.join(folder, "rtcl"), os.path.join(folder, "povray")
    os.makedirs(rtcl_dir)
    os.makedirs(pov_dir)
    doc = load_scene(scene)
    with open(os.path.join(pov_dir, "scene.pov"), "w", encoding="utf-8") as f:
        f.write(to_sdl(doc, args.size, doc["max_depth"], scene))
    plain = rtcl_command(rtcl, scene, args.size, "render.png")
    pov = povray_command(povray, args.size, args.threads)
    jobs = [("rtcl", lambda: time_once(plain, rtcl_dir, "render.png")[:2]),
            ("povray", lambda: time_once(pov, pov_dir, "render.png")[:2])]
    interleaved(jobs, 1)  # warm-up: caches, page cache
    times = interleaved(jobs, args.runs)
    verbose = rtcl_command(rtcl, scene, args.size, "render.png", verbose=True)
    breakdowns = [parse_breakdown(time_once(verbose, rtcl_dir, "render.png")[2])
                  for _ in range(args.runs)]
    return times, breakdowns


def report(args, name, device, cpu, version, loads, times, breakdown):
    walls = {name: [t[0] for t in runs] for name, runs in times.items()}
    cpus = {name: [t[1] for t in runs] for name, runs in times.items()}
    rtcl_s, pov_s = median(walls["rtcl"]), median(walls["povray"])
    ratio, verdict = ratio_verdict(rtcl_s, pov_s, TARGET)
    lines = [
        "time to image, whole process, %dx%d" % args.size,
        "scene: %s" % name,
        "rtcl device: %s" % device,
        "cpu: %s, %d CPUs" % (cpu or "unknown (no lscpu)", os.cpu_count() or 0),
        "povray: %s, +WT%d" % (version, args.threads),
        "load average before: %.2f %.2f %.2f, after: %.2f %.2f %.2f" % (loads[0] + loads[1]),
        "rtcl:   %s" % summary(walls["rtcl"]),
        "povray: %s" % summary(walls["povray"]),
        "rtcl runs:   %s s" % " ".join("%.3f" % w for w in walls["rtcl"]),
        "povray runs: %s s" % " ".join("%.3f" % w for w in walls["povray"]),
        "ratio rtcl/povray (medians): %.3f; target <= %.2f: %s" % (ratio, TARGET, verdict),
        "CPU time (user + system, all threads), median: rtcl %.3f s, povray %.3f s, "
        "ratio %.3f" % (median(cpus["rtcl"]), median(cpus["povray"]),
                        median(cpus["rtcl"]) / max(median(cpus["povray"]), 1e-9)),
        "rtcl -v breakdown (median of %d): %s" % (args.runs, format_breakdown(breakdown)),
    ]
    return "\n".join(lines) + "\n"


def run(args):
    rtcl = locations.find_rtcl(args.rtcl)
    rtcl = shutil.which(rtcl) or rtcl
    povray = shutil.which(args.povray)
    if povray is None:
        raise RunError("%s not found on PATH (apt-get install povray)" % args.povray)
    if not os.access(rtcl, os.X_OK):
        raise RunError("%s is not an executable (make)" % args.rtcl)
    version = povray_version(povray)
    with tempfile.TemporaryDirectory(prefix="rtcl-time-to-image-") as folder:
        scene, name = scene_file(args, folder)
        device = rtcl_device(rtcl, folder)
        before = os.getloadavg()
        times, breakdowns = measure(args, rtcl, povray, folder, scene)
        after = os.getloadavg()
    return report(args, name, device, cpu_model(), version, (before, after), times,
                  median_breakdown(breakdowns))


@interruptible
def main(argv=None):
    args = parse_arguments(argv)
    prog = program_name()
    try:
        with files.committed_files_allowed(args.update_committed):
            files.check_input_files([args.scene])   # before minutes of runs
            if args.scene:   # the scene and its meshes: no output replaces them
                files.reading([args.scene, *(mesh["file"] for mesh
                                             in load_scene(args.scene).get("meshes", []))])
            if args.output:
                files.check_outputs([args.output])
            text = run(args)
            if args.output:
                files.write_text(args.output, text)
    except (RunError, SceneError, locations.NotFound) as e:
        print("%s: %s" % (prog, e), file=sys.stderr)
        return 1
    except OSError as e:
        print("%s: %s" % (prog, os_error_message(e)), file=sys.stderr)
        return 1
    sys.stdout.write(text)
    return 0

