"""Benchmark every rtcl kernel over a sweep of geometries on one device (issue 4).

Runs each configuration as one call

    rtcl -k KERNEL -w WxH [--groups GXxGY] [--batch N] --flops F.npy --stats S.json -r N

(rtcl counts flops in one untimed run, then times one warm-up and N launches from
OpenCL profiling events and reports their median, min and max).  The sweep:

  - naive and wavefront: every work-group shape of --workgroups (the wavefront
    honours only -w: it sets the primary-ray launch's work-group and the size of
    the 1D bounce launches' groups);
  - cyclic, dynamic and persistent: every shape at rtcl's default group count
    ("enough to fill the device"), then that count scaled by --group-scales in
    total (about sqrt(s) per dimension); persistent at every --batch;
  - the paper's geometries: naive 16x10; cyclic 8x8, 25x25 groups; dynamic 8x8,
    10x10; persistent 8x8, 10x10, batch 1 (dynamic's); wavefront 8x8;
  - serial (one work-item, ~1000x slower) only with --serial, one timed launch.
--paper-only runs the paper's geometries alone.  A configuration rtcl refuses
(a work-group too large for the device, a buffer that does not fit, ...) is a
table row marked skipped with rtcl's one-line reason; so is one whose geometry
repeats a row above.

Into -o/--out DIR (by default a new folder rtcl-results/<device-slug>-<YYYYmmdd-HHMMSS>
under the current folder; with --update-committed, the committed
docs/results/<device-slug> of the source tree, as `make results` does) it writes
  bench.csv   one row per configuration, every figure of rtcl's --stats;
  bench.md    the table, sorted by kernel then time, the best of each kernel in
              bold, under a header naming device, driver, OpenCL version, scene,
              size, depth, commit, date, command line and the FP32 peak's formula;
and with --scaling, for one kernel and geometry (default: the sweep's fastest,
else dynamic 8x8 at the default groups; or --scaling-config) at several image
sizes and sphere counts (scenes from tools/genscene.py --seed 2009):
  scaling.csv, scaling.md   time per megapixel and per megapixel x sphere, and
              least-squares checks of linearity (R^2, largest deviation).
Every file is written to a temporary file and renamed, and only once every run
has finished: a failed or interrupted benchmark writes nothing.  A file tracked by
git is never replaced (without --update-committed): with --out naming one, the
benchmark stops before its first run.

The FP32 peak: NVIDIA H100 / H200 (GH100) from a built-in table, SMs (rtcl's
compute units) x 128 FP32 lanes x 2 (FMA) x boost clock; a CPU under PoCL as
physical cores x SIMD lanes (from /proc/cpuinfo: avx512f 16, avx2+fma 8) x FMA
units per core (--fma-units: the flags do not tell) x 2 x clock (rtcl's
max_clock_mhz); --peak-gflops gives it for any device.  Where it stays unknown
the benchmark runs all the same, its "% of FP32 peak" column empty.

    rtcl-bench -p 0 -d 0 --fma-units 1            # the full sweep, 2000x2000
    rtcl-bench --paper-only --peak-gflops 100      # the paper's geometries only
    rtcl-bench --quick --scaling -o smoke         # a smoke run of a few minutes
    make bench DEVICE="-p 0 -d 0" BENCH="--scaling"
    make results DEVICE="-p 0 -d 0"               # regenerate docs/results/<device>
(tools/bench.py in a checkout is the same command.)
"""

import pathlib
import shlex
import sys
import tempfile

from .. import bench_report, files, locations, scaling
from ..bench_options import parse_arguments
from ..bench_plan import plan
from ..bench_run import BenchProgress, SilentProgress, probe, run_sweep
from ..interrupts import exit_status, interruptible, signal_name
from ..peak import find_peak, read_cpuinfo
from ..report import device_slug, git_describe, one_line, to_csv, utc_now
from ..runner import RtclFailed, Settings, common_options, describe
from ..usage import UsageError, command_name, program_name, report_error

OUTPUT_NAMES = ("bench.csv", "bench.md", "scaling.csv", "scaling.md")


def output_folder(arguments, slug):
    """Returns where the files go: --out, docs/results/<slug> with
    --update-committed, else a new folder rtcl-results/<slug>-<date-time>."""
    if arguments.update_committed:
        return locations.committed_results() / slug
    if arguments.out is not None:
        return pathlib.Path(arguments.out)
    return locations.new_results_folder(slug)


def run_benchmark(arguments, temp_dir, command_line):
    """Runs everything; returns {name: text} of the files to write and the device slug."""
    rtcl = locations.find_rtcl(arguments.rtcl)
    settings = Settings(rtcl, common_options(arguments), arguments.repeat, temp_dir)
    try:
        device_stats = probe(settings, SilentProgress(1))
    except RtclFailed as error:
        raise RtclFailed(f"rtcl failed on an 8x8 probe run: {error.reason}", error.command,
                         error.returncode, error.stderr) from None
    peak = find_peak(device_stats, arguments, read_cpuinfo())
    print(f"FP32 peak: {peak.formula}", file=sys.stderr)
    meta = {"commit": git_describe(), "repeat": arguments.repeat, "command": command_line,
            "date": utc_now()}
    outputs = {}
    configs = []
    if not arguments.no_sweep:
        configs = plan(arguments.kernels, arguments.workgroups, arguments.group_scales,
                       arguments.batches, arguments.paper_only, arguments.serial)
        run_sweep(configs, settings, BenchProgress(len(configs)))
        outputs["bench.csv"] = to_csv(
            bench_report.CSV_COLUMNS, [bench_report.csv_row(c, peak.gflops) for c in configs])
        outputs["bench.md"] = bench_report.render_bench_md(configs, peak, meta)
    if arguments.scaling:
        choice = scaling.scaling_choice(arguments, configs)
        print(f"scaling: {describe(*choice[:4])} ({choice[4]})", file=sys.stderr)
        points = scaling.run_scaling(arguments, settings, choice, temp_dir)
        outputs["scaling.csv"] = to_csv(
            scaling.SCALING_COLUMNS, [scaling.scaling_row(p) for p in points])
        outputs["scaling.md"] = scaling.render_scaling_md(points, choice, meta)
    return outputs, device_slug(device_stats["device"])


@interruptible
def main(argv=None):
    program = program_name()
    argv = sys.argv[1:] if argv is None else argv
    command_line = shlex.join([command_name(), *argv])
    try:
        arguments = parse_arguments(argv)
        with files.committed_files_allowed(arguments.update_committed):
            outputs = benchmark(arguments, command_line)
    except UsageError as error:
        return report_error(program, error, 2)
    except RtclFailed as error:
        return report_error(program, error)
    except (OSError, ValueError, KeyError, locations.NotFound) as error:
        return report_error(program, one_line(error))
    except KeyboardInterrupt as error:
        print(f"\n{program}: interrupted ({signal_name(error)}); nothing written",
              file=sys.stderr)
        return exit_status(error)
    for path in outputs:
        print(f"{program}: wrote {path}", file=sys.stderr)
    return 0



def benchmark(arguments, command_line):
    """Runs the benchmark and writes its files; returns their paths."""
    # What would be refused at the end is refused before hours of runs.
    files.check_input_files([arguments.scene])
    files.reading([arguments.scene])
    if arguments.update_committed:
        locations.committed_results()
    elif arguments.out is not None:
        files.check_output_folder(arguments.out, OUTPUT_NAMES)
    with tempfile.TemporaryDirectory(prefix="rtcl-bench-") as temp_name:
        texts, slug = run_benchmark(arguments, pathlib.Path(temp_name), command_line)
    out_dir = output_folder(arguments, slug)
    outputs = {out_dir / name: text for name, text in texts.items()}
    files.write_all(outputs)
    return outputs
