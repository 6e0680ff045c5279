#!/usr/bin/python3
"""Kernel time against samples per pixel (issue 12 item 1: "cost is linear in N").

Runs rtcl -r R --spp N for N = 1, 2, 4, ..., --max-spp with one kernel, and
writes spp.md (a table: the median kernel time over the R timed frames, min and
max, milliseconds per sample, and the time over N times the one-sample time)
and spp.csv to --out. A benchmark, not a test: it asserts nothing.

    tools/bench_spp.py --size 200x150 -r 5 --out docs/results/pocl-amd-epyc/spp
"""
import argparse
import csv
import pathlib
import sys
import tempfile

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from rtcl_tools import runner  # noqa: E402


def parse_arguments(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rtcl", default=str(pathlib.Path(__file__).resolve().parent.parent
                                              / "rtcl"))
    parser.add_argument("-k", "--kernel", default="dynamic")
    parser.add_argument("-s", "--scene")
    parser.add_argument("--size", default="200x150")
    parser.add_argument("--depth")
    parser.add_argument("-p", "--platform")
    parser.add_argument("-d", "--device")
    parser.add_argument("-r", "--repeat", type=int, default=5)
    parser.add_argument("--max-spp", type=int, default=64)
    parser.add_argument("--out", type=pathlib.Path, required=True)
    return parser.parse_args(argv)


def measure(arguments):
    """Returns [(N, stats)] for N = 1, 2, 4, ... up to --max-spp."""
    counts = [1]
    while counts[-1] * 2 <= arguments.max_spp:
        counts.append(counts[-1] * 2)
    progress = runner.Progress(len(counts))
    rows = []
    with tempfile.TemporaryDirectory() as temp:
        for n in counts:
            settings = runner.Settings(arguments.rtcl,
                                       runner.common_options(arguments) + ["--spp", str(n)],
                                       arguments.repeat, pathlib.Path(temp))
            run = runner.run_rtcl(settings, progress, f"spp{n}", arguments.kernel, flops=False)
            rows.append((n, run.stats))
    return rows


def write_report(arguments, rows):
    arguments.out.mkdir(parents=True, exist_ok=True)
    one = rows[0][1]["kernel_ms"]
    stats = rows[0][1]
    lines = [f"# Kernel time against samples per pixel ({arguments.kernel})", "",
             f"Device: {stats['device']}. Scene {stats['scene']}, {stats['width']}x"
             f"{stats['height']}, max depth {stats['max_depth']}; median of "
             f"{arguments.repeat} timed frames after a warm-up (`tools/bench_spp.py "
             f"--size {arguments.size} -r {arguments.repeat} -k {arguments.kernel}`).", "",
             "| spp | passes | median ms | min ms | max ms | ms per sample | time / (N x time at 1) |",
             "|---:|---:|---:|---:|---:|---:|---:|"]
    with open(arguments.out / "spp.csv", "w", newline="") as f:
        table = csv.writer(f)
        table.writerow(["spp", "passes", "kernel_ms", "kernel_ms_min", "kernel_ms_max",
                        "ms_per_sample", "linearity"])
        for n, s in rows:
            per_sample, linearity = s["kernel_ms"] / n, s["kernel_ms"] / (n * one)
            table.writerow([n, s.get("passes", 1), s["kernel_ms"], s["kernel_ms_min"],
                            s["kernel_ms_max"], per_sample, linearity])
            lines.append(f"| {n} | {s.get('passes', 1)} | {s['kernel_ms']:.2f} | "
                         f"{s['kernel_ms_min']:.2f} | {s['kernel_ms_max']:.2f} | "
                         f"{per_sample:.3f} | {linearity:.2f} |")
    (arguments.out / "spp.md").write_text("\n".join(lines) + "\n")


def main(argv=None):
    arguments = parse_arguments(argv)
    try:
        rows = measure(arguments)
    except runner.RtclFailed as error:
        print(f"bench_spp: {error}", file=sys.stderr)
        return 1
    write_report(arguments, rows)
    print((arguments.out / "spp.md").read_text(), end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
