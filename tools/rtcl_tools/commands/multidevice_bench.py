"""Multi-device and MPI benchmark (issue 13): the same job on one device, on
several devices in one process, and over MPI ranks; the time of each (median of
--runs), each device's share and the device-level efficiency; and the overhead
per piece.

One image (the default): the devices share it in row bands (--piece-rows); the
table gives the image time (rtcl's frame_ms: the frame's wall time, on one
device as over several; kernel_ms from an rtcl without it) and the whole
process's wall time;
the overhead per band comes from the same image cut in few and in many bands
(--scan-rows), and the scan shows which band size keeps it low.

    rtcl-multidevice-bench --single 1:0 --multi 1:0,0:0 [--mpi-np 2 --mpi-devices 0:0]
        [--size 2000x2000] [--spp 16] [--scan-rows 8,32,128,500] [-r 3] [-o NAME.md]

(tools/multidevice_bench.py in a checkout is the same command.)  The report goes
to stdout and, with -o FILE, to FILE, which is never a file tracked by git
(docs/results/multidevice/NAME.md) unless --update-committed.

An animation (--frames A:B): whole frames are the pieces; the overhead per
piece is a tiny frame's (render time negligible).

--single and --multi are --devices lists (platform:device, see rtcl --list-devices);
--mpi-np N adds `mpirun -np N rtcl --mpi --devices MPI_DEVICES` (each rank the
listed devices; under PoCL set POCL_DEVICES per rank with --mpi-env). The
target on a GPU+CPU node: --multi no slower than --single on a >= 1 s render.
"""
import argparse
import json
import os
import pathlib
import re
import shlex
import statistics
import subprocess
import sys
import tempfile
import time

from .. import files, locations
from ..interrupts import interruptible
from ..runner import RtclFailed, rtcl_reason
from ..usage import (add_rtcl_option, add_update_committed, os_error_message, program_name,
                     report_error)


def run(command, env, stats):
    start = time.perf_counter()
    result = subprocess.run(command, capture_output=True, text=True, env=env, timeout=3600)
    wall = (time.perf_counter() - start) * 1e3
    if result.returncode != 0:
        raise RtclFailed(f"{shlex.join(command)} failed (exit {result.returncode}): "
                         f"{rtcl_reason(result.stderr)}", command, result.returncode,
                         result.stderr)
    doc = json.loads(pathlib.Path(stats).read_text())
    doc["process_ms"] = wall
    return doc


def shares_of(doc):
    md = doc.get("multidevice")
    if not md:
        return 1.0, "one device, whole image"
    return md["device_efficiency"], ", ".join(
        f"{d.get('rank', 0)}/{d['platform']}:{d['index']} {d['pieces']}" for d in md["devices"])


def image_time(doc):
    """A frame's wall time: frame_ms (one device's launches with the gaps
    between them, as several devices are timed), else kernel_ms."""
    return doc.get("frame_ms", doc["kernel_ms"])


def run_repeated(command, env, runs, workdir, output):
    """The --stats documents of `runs` runs of command, writing output."""
    docs = []
    for i in range(runs):
        stats = os.path.join(workdir, f"s{i}.json")
        docs.append(run([*command, "--stats", stats, "-o", os.path.join(workdir, output)],
                        env, stats))
    return docs


def measure_image(label, command, env, runs, workdir):
    docs = run_repeated(command, env, runs, workdir, "i.ppm")
    image_ms = statistics.median(image_time(d) for d in docs)
    best = sorted(docs, key=image_time)[len(docs) // 2]
    efficiency, shares = shares_of(best)
    return {"label": label, "image_ms": image_ms,
            "process_ms": statistics.median(d["process_ms"] for d in docs),
            "efficiency": efficiency, "shares": shares, "bands": best.get(
                "multidevice", {}).get("bands", 1), "command": " ".join(command)}


def configurations(args, base):
    """(label, command) for one device, several devices (dynamic and static) and,
    with --mpi-np, mpirun: the runs both modes compare."""
    configs = [(f"one device {args.single}", [*base, "--devices", args.single]),
               (f"--devices {args.multi} (dynamic)", [*base, "--devices", args.multi]),
               (f"--devices {args.multi} --split static",
                [*base, "--devices", args.multi, "--split", "static"])]
    if args.mpi_np:
        mpi = ["mpirun", "--oversubscribe", "-np", str(args.mpi_np)]
        if args.mpi_env:
            mpi += ["-x", args.mpi_env]
        configs.append((f"mpirun -np {args.mpi_np}, each --devices {args.mpi_devices}",
                        [*mpi, *base, "--mpi", "--devices", args.mpi_devices]))
    return configs


def image_main(args, env):
    base = [args.rtcl, "-q", "-k", args.kernel, "--size", args.size, "--spp", str(args.spp)]
    configs = configurations(args, base)
    rows, scan = [], []
    with tempfile.TemporaryDirectory() as workdir:
        for label, command in configs:
            rows.append(measure_image(label, command, env, args.runs, workdir))
            print(f"{label}: {rows[-1]['image_ms']:.1f} ms", file=sys.stderr)
        for n in (int(x) for x in args.scan_rows.split(",") if x):
            command = [*base, "--devices", args.multi, "--split", "static", "--piece-rows",
                       str(n)]
            scan.append(measure_image(f"--piece-rows {n}", command, env, args.runs, workdir))
            print(f"--piece-rows {n}: {scan[-1]['image_ms']:.1f} ms", file=sys.stderr)
    devices = len(args.multi.split(","))
    lines = [f"# Multi-device: one {args.size} image at {args.spp} spp, kernel {args.kernel}, "
             f"median of {args.runs}", "",
             "| configuration | image ms | speed-up | process ms | device-level efficiency | "
             "bands per device (rank/platform:device) |", "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['label']} | {r['image_ms']:.1f} | "
                     f"{rows[0]['image_ms'] / r['image_ms']:.2f}x | {r['process_ms']:.0f} | "
                     f"{100 * r['efficiency']:.1f}% | {r['shares']} |")
    if len(scan) >= 2:
        few, many = max(scan, key=lambda r: -r["bands"]), max(scan, key=lambda r: r["bands"])
        per_band = ((many["image_ms"] - few["image_ms"]) * devices /
                    max(1, many["bands"] - few["bands"]))
        lines += ["", f"Band size on --devices {args.multi} --split static:", "",
                  "| --piece-rows | bands | image ms | efficiency |", "|---|---|---|---|"]
        lines += [f"| {r['label'].split()[-1]} | {r['bands']} | {r['image_ms']:.1f} | "
                  f"{100 * r['efficiency']:.1f}% |" for r in scan]
        lines += ["", f"Overhead per band (({many['bands']} bands − {few['bands']} bands) on "
                  f"{devices} devices): {per_band:.2f} ms"]
    lines += ["", "Commands:", ""] + [f"    {r['command']}" for r in rows]
    return "\n".join(lines) + "\n"


def measure(label, command, env, runs, workdir):
    docs = run_repeated(command, env, runs, workdir, "f.ppm")
    best = sorted(docs, key=lambda d: d["wall_ms"])[len(docs) // 2]
    efficiency, shares = shares_of(best)
    return {"label": label, "wall_ms": statistics.median(d["wall_ms"] for d in docs),
            "efficiency": efficiency, "shares": shares, "command": " ".join(command)}


def parse_arguments(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    add_rtcl_option(parser)
    parser.add_argument("--single", required=True)
    parser.add_argument("--multi", required=True)
    parser.add_argument("--mpi-np", type=int, default=0)
    parser.add_argument("--mpi-devices", default="0:0")
    parser.add_argument("--mpi-env", default="", help="VAR=VALUE passed to every rank")
    parser.add_argument("--frames", default=None,
                        help="an animation A:B instead of one image")
    parser.add_argument("--spp", type=int, default=1)
    parser.add_argument("--scan-rows", default="",
                        help="band sizes (rows) to time on --multi, e.g. 8,32,128,600")
    parser.add_argument("--size", default="1000x1000")
    parser.add_argument("-k", "--kernel", default="dynamic")
    parser.add_argument("-r", "--repeat", "--runs", dest="runs", type=int, default=3,
                        help="runs of each configuration (default %(default)s)")
    parser.add_argument("-o", "--out", metavar="FILE",
                        help="also write the report to FILE")
    add_update_committed(parser)
    args = parser.parse_args(argv)
    # Refused here, before any run (-r 0 once ended in statistics.StatisticsError).
    if args.runs < 1:
        parser.error(f"-r/--repeat {args.runs}: expected at least 1 run of each configuration")
    if args.spp < 1:
        parser.error(f"--spp {args.spp}: expected at least 1")
    if args.mpi_np < 0:
        parser.error(f"--mpi-np {args.mpi_np}: expected 0 (no MPI run) or more ranks")
    if not re.fullmatch(r"([1-9][0-9]*(,[1-9][0-9]*)*)?", args.scan_rows):
        parser.error(f"--scan-rows: expected band sizes such as 8,32,128, got "
                     f"{args.scan_rows!r}")
    if args.frames is not None:
        match = re.fullmatch(r"([0-9]+):([0-9]+)", args.frames)
        if not match or int(match.group(1)) > int(match.group(2)):
            parser.error(f"--frames: expected A:B with A <= B, got {args.frames!r}")
    return args


@interruptible
def main(argv=None):
    args = parse_arguments(argv)
    program = program_name()
    try:
        with files.committed_files_allowed(args.update_committed):
            if args.out:
                files.check_outputs([args.out])   # before the runs, not after
            args.rtcl = locations.find_rtcl(args.rtcl)
            text = image_main(args, environment()) if not args.frames else \
                frames_main(args, environment())
            print(text)
            if args.out:
                files.write_text(args.out, text)
    except OSError as error:
        return report_error(program, os_error_message(error))
    except (RtclFailed, subprocess.SubprocessError, locations.NotFound) as error:
        return report_error(program, error)
    return 0


def environment():
    """The runs' environment: mpirun is allowed to run as root (containers)."""
    return {**os.environ, "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}


def frames_main(args, env):
    """--frames A:B: whole frames are the pieces; returns the report."""
    base = [args.rtcl, "-q", "-k", args.kernel, "--size", args.size, "--frames", args.frames]
    configs = configurations(args, base)
    rows = []
    with tempfile.TemporaryDirectory() as workdir:
        for label, command in configs:
            rows.append(measure(label, command, env, args.runs, workdir))
            print(f"{rows[-1]['label']}: {rows[-1]['wall_ms']:.1f} ms", file=sys.stderr)
        first, last = (int(x) for x in args.frames.split(":"))
        tiny = [args.rtcl, "-q", "-k", args.kernel, "--size", "8x8", "--frames", args.frames,
                "--devices", args.single]
        overhead = measure("overhead", tiny, env, args.runs, workdir)
    frames = last - first + 1
    lines = [f"# Multi-device: {args.frames} ({frames} frames) at {args.size}, kernel "
             f"{args.kernel}, median of {args.runs}", "",
             "| configuration | wall ms | ms/frame | speed-up | device-level efficiency | "
             "frames per device (rank/platform:device) |", "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['label']} | {r['wall_ms']:.1f} | {r['wall_ms'] / frames:.1f} | "
                     f"{rows[0]['wall_ms'] / r['wall_ms']:.2f}x | {100 * r['efficiency']:.1f}% | "
                     f"{r['shares']} |")
    lines += ["", f"Overhead per piece (a whole frame at 8x8 on {args.single}, set-up, build "
              f"from the cache, upload, launch, read-back, staging): "
              f"{overhead['wall_ms'] / frames:.1f} ms", "", "Commands:", ""]
    lines += [f"    {r['command']}" for r in rows]
    return "\n".join(lines) + "\n"
