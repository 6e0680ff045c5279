"""Kernel time against samples per pixel (issue 12 item 1: "cost is linear in N").

Runs rtcl -r R --spp N for N = 1, 2, 4, ..., --max-spp with one kernel, and
writes spp.md (a table: the median kernel time over the R timed frames, min and
max, milliseconds per sample, and the time over N times the one-sample time)
and spp.csv into -o/--out DIR (by default a new folder
rtcl-results/<device-slug>-spp-<YYYYmmdd-HHMMSS>). A benchmark, not a test: it
asserts nothing. A file tracked by git is replaced only with --update-committed.

    rtcl-bench-spp --size 200x150 -r 5 -o spp
    tools/bench_spp.py --size 200x150 -r 5 -o docs/results/pocl-amd-epyc/spp --update-committed
"""
import argparse
import pathlib
import re
import sys
import tempfile

from .. import files, locations, runner
from ..interrupts import interruptible
from ..report import device_slug, one_line, to_csv
from ..usage import (add_rtcl_option, add_update_committed, command_name, program_name,
                     report_error)

OUTPUT_NAMES = ("spp.md", "spp.csv")
MAX_SPP = 65536   # rtcl's --spp limit (SCENE_MAX_SAMPLES)
CSV_COLUMNS = ("spp", "passes", "kernel_ms", "kernel_ms_min", "kernel_ms_max",
               "ms_per_sample", "linearity")


def parse_arguments(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    add_rtcl_option(parser)
    parser.add_argument("-k", "--kernel", default="dynamic")
    parser.add_argument("-s", "--scene")
    parser.add_argument("--size", default="200x150")
    parser.add_argument("--depth")
    parser.add_argument("-p", "--platform")
    parser.add_argument("-d", "--device")
    parser.add_argument("-r", "--repeat", type=int, default=5,
                        help="timed frames per sample count (default %(default)s)")
    parser.add_argument("--max-spp", type=int, default=64,
                        help=f"the largest sample count, 1 ... {MAX_SPP} (rtcl's --spp; "
                             "default %(default)s)")
    parser.add_argument("-o", "--out", type=pathlib.Path, metavar="DIR",
                        help="the folder to write into (default: a new folder "
                             "rtcl-results/<device-slug>-spp-<YYYYmmdd-HHMMSS>)")
    add_update_committed(parser)
    arguments = parser.parse_args(argv)
    # Refused here, not by rtcl after the smaller counts' runs.
    if not 1 <= arguments.max_spp <= MAX_SPP:
        parser.error(f"--max-spp {arguments.max_spp}: expected 1 ... {MAX_SPP} (rtcl's "
                     "--spp limit)")
    if arguments.repeat < 1:
        parser.error(f"--repeat {arguments.repeat}: expected at least 1")
    if not re.fullmatch(r"[1-9][0-9]{0,4}x[1-9][0-9]{0,4}", arguments.size):
        parser.error(f"--size: expected WxH with positive integers, got {arguments.size!r}")
    if arguments.depth is not None and not (re.fullmatch(r"[0-9]{1,2}", arguments.depth)
                                            and int(arguments.depth) <= 64):
        parser.error(f"--depth: expected 0 ... 64, got {arguments.depth!r}")
    return arguments


def measure(arguments):
    """Returns [(N, stats)] for N = 1, 2, 4, ... up to --max-spp."""
    counts = [1]
    while counts[-1] * 2 <= arguments.max_spp:
        counts.append(counts[-1] * 2)
    rtcl = locations.find_rtcl(arguments.rtcl)
    progress = runner.Progress(len(counts))
    rows = []
    with tempfile.TemporaryDirectory() as temp:
        for n in counts:
            settings = runner.Settings(rtcl,
                                       runner.common_options(arguments) + ["--spp", str(n)],
                                       arguments.repeat, pathlib.Path(temp))
            run = runner.run_rtcl(settings, progress, f"spp{n}", arguments.kernel, flops=False)
            rows.append((n, run.stats))
    return rows


def render_report(arguments, rows):
    """Returns {file name: text}: spp.md and spp.csv."""
    one = rows[0][1]["kernel_ms"]
    stats = rows[0][1]
    lines = [f"# Kernel time against samples per pixel ({arguments.kernel})", "",
             f"Device: {stats['device']}. Scene {stats['scene']}, {stats['width']}x"
             f"{stats['height']}, max depth {stats['max_depth']}; median of "
             f"{arguments.repeat} timed frames after a warm-up (`{command_name()} "
             f"--size {arguments.size} -r {arguments.repeat} -k {arguments.kernel}`).", "",
             "| spp | passes | median ms | min ms | max ms | ms per sample | time / (N x time at 1) |",
             "|---:|---:|---:|---:|---:|---:|---:|"]
    table = []
    for n, s in rows:
        per_sample, linearity = s["kernel_ms"] / n, s["kernel_ms"] / (n * one)
        table.append(dict(zip(CSV_COLUMNS, (n, s.get("passes", 1), s["kernel_ms"],
                                            s["kernel_ms_min"], s["kernel_ms_max"],
                                            per_sample, linearity))))
        lines.append(f"| {n} | {s.get('passes', 1)} | {s['kernel_ms']:.2f} | "
                     f"{s['kernel_ms_min']:.2f} | {s['kernel_ms_max']:.2f} | "
                     f"{per_sample:.3f} | {linearity:.2f} |")
    return {"spp.md": "\n".join(lines) + "\n", "spp.csv": to_csv(CSV_COLUMNS, table)}


@interruptible
def main(argv=None):
    arguments = parse_arguments(argv)
    program = program_name()
    try:
        with files.committed_files_allowed(arguments.update_committed):
            files.check_input_files([arguments.scene])   # before the runs, not after
            files.reading([arguments.scene])
            if arguments.out is not None:
                files.check_output_folder(arguments.out, OUTPUT_NAMES)
            rows = measure(arguments)
            out = arguments.out or locations.new_results_folder(
                device_slug(rows[0][1]["device"]) + "-spp")
            texts = render_report(arguments, rows)
            files.write_all({out / name: text for name, text in texts.items()})
    except runner.RtclFailed as error:
        return report_error(program, error)
    except (OSError, locations.NotFound) as error:
        return report_error(program, one_line(error))
    print(texts["spp.md"], end="")
    print(f"{program}: results in {out}", file=sys.stderr)
    return 0
