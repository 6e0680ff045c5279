"""Run the 2009 paper's experiment (section 5, Table 1, Figures 6 and 7) with rtcl.

On one OpenCL device, runs
  - serial:  one work-item renders every pixel (the paper's 90.56 s baseline);
  - naive:   16x10 work-groups, one work-item per pixel;
  - cyclic:  8x8 work-groups, 25x25 groups (the paper's 10x10 grid of chunks);
  - dynamic: 8x8 work-groups, 10x10 groups fetching 8x8 chunks;
  - persistent (beyond the paper, docs/wavefront.md): the dynamic kernel's
    geometry, 8x8 work-groups and 10x10 groups, each work-item fetching one pixel
    at a time (--batch 1);
  - wavefront (beyond the paper): 8x8 work-groups for the primary-ray launch
    (the bounce launches are 1D, 64 work-items a group); the wavefront honours
    only -w, not --groups or --batch;
  - the CPU reference, once: a native single-core baseline (skip: --no-reference);
  - unless --no-sweep, a small sweep of every parallel kernel: every work-group
    shape of SWEEP_WORKGROUPS at rtcl's default group count, then, for cyclic,
    dynamic and persistent, the fastest shape with the group count scaled up to
    4x and with the paper-like group count (-r 3 per sweep run).  Each kernel's
    fastest sweep entry is its "best of sweep" row, with that entry's own time:
    it is not run again, so that no re-timing can make it slower than another
    entry of the sweep.
The paper measured neither persistent nor wavefront (its section 3.4 proposed
such schemes and judged them impossible on a GPU), so their paper cells are empty.
Every run is one `rtcl --flops --stats` call: rtcl counts flops in one launch and
times others without counting.  For the wavefront, rtcl counts every launch of the
frame (the primary-ray launch, then one per bounce) and writes their work-items
one after the other; its parallel efficiency and its histogram cover the
work-items of all its launches.

Every run uses `--accel none` (the paper's brute force, so that Table 1 stays
comparable with the paper's) unless --accel bvh asks for the study of divergent
BVH traversal (issue 11 item 8); --scene FILE runs it on another scene.  The study
is named <device-slug> for the paper's study (--accel none, built-in scene), else
<device-slug>-<accel>-<scene stem> (e.g. nvidia-h200-bvh-paper60,
nvidia-h200-bvh-lake-10).  It writes into -o/--out DIR; by default into a new folder
rtcl-results/<study>-<YYYYmmdd-HHMMSS> under the current folder.  No file tracked
by git is ever replaced or removed, unless --update-committed asks to regenerate
the committed results: the folder is then docs/results/<study> of the source tree
(`make results` does that):
  results.json       every run's command and rtcl statistics, the study's accel,
                     scene, size and depth, and each run's histogram of flops per
                     work-item (50 bins, mean, max, min): all the figures need;
  table1.md          Table 1, ours beside the paper's, with the commands used;
  speedup.png        Figure 6: speedup per implementation, a panel per baseline
                     (ours over the serial kernel, ours over the CPU reference,
                     the paper's over its CPU program), log axes from 1;
  histograms.png     Figure 7: flops per work-item, paper(-like) geometries;
  histograms_best.png  the same for the sweep's best geometries (with the sweep).
The per-work-item .npy files (tens of MB each) are deleted as soon as their
histogram is in memory.  The figures need matplotlib: without it (or with
--no-plots) results.json and table1.md are written, one line on stderr says so,
and `rtcl-experiments --replot DIR` on a machine with matplotlib draws them.

--replot DIR runs no rtcl: it reads DIR/results.json and rewrites DIR/table1.md and
every figure with the current report code (the best-of-sweep rows taken from the
stored sweep runs, the table saying when and by which commit it was regenerated).
A results.json written before it stored histograms leaves histograms*.png as they
are.  It takes only --no-plots, --peak-gflops, --fma-units and --update-committed
(needed to redraw committed results); any other option is refused.

While it runs, the study keeps the runs it finished in its results folder
(study-progress.json, rewritten after every run).  Interrupted (Ctrl-C, SIGTERM,
SIGHUP: one line, no traceback, exit status 128 + the signal, the temporary folder
removed) or stopped by a failed rtcl run, it says so and gives the command that
goes on: --resume DIR runs the study with the options it started with (only
--rtcl may be given again), takes the finished runs from the journal without
running them, and removes the journal once the results are written.

table1.md ends with the bounds of each kernel (docs/RENDERING.md): its time at 100 %
SIMD efficiency and the time its counted flops take at the device's FP32 peak.  The
peak comes from --peak-gflops, else a built-in table (NVIDIA H100, H200, A100), else,
for a CPU, /proc/cpuinfo with --fma-units; results.json keeps it (for a CPU with the
fields of /proc/cpuinfo it came from), so --replot on another machine uses the
measuring machine's, and --replot --fma-units N computes a CPU's again (refused for
a GPU's study, or an older CPU study's without those fields on another CPU).  On a
CPU the SIMD columns say they do not apply: SIMD efficiency is modelled on a GPU's
warps of 32 in lock-step, which PoCL does not have.

    rtcl-experiments -p 0 -d 0                 # the full 2000x2000 experiment
    rtcl-experiments --quick -o quick          # 400x400, a smaller sweep, into quick/
    rtcl-experiments --resume quick            # go on after an interruption
    rtcl-experiments -p 0 -d 0 --accel bvh     # the study with the BVH
    rtcl-experiments -p 0 -d 0 --accel bvh -s lake/lake-10.json --no-plots
    make experiments DEVICE="-p 0 -d 0"        # the same through make
    make results DEVICE="-p 0 -d 0"            # regenerate docs/results/<device>
    rtcl-experiments --replot docs/results/nvidia-h100-80gb-hbm3 --update-committed
(tools/experiments.py in a checkout is the same command.)
"""

import argparse
import pathlib
import sys
import tempfile

from ..requirements import require

require("numpy")  # the flops files; matplotlib is optional (see above)

from .. import files, locations  # noqa: E402
from ..experiment import (FIGURES, PROGRESS_NAME, Journal, load_journal,  # noqa: E402
                          replot, results_folder, run_experiment, study_folder,
                          study_options, write_outputs)
from ..flops import FlopsFileError  # noqa: E402
from ..interrupts import exit_status, interruptible, signal_name  # noqa: E402
from ..paper import DEFAULT_REPEAT, QUICK_SIZE  # noqa: E402
from ..report import one_line  # noqa: E402
from ..runner import RtclFailed  # noqa: E402
from ..usage import (add_rtcl_option, add_update_committed, command_name,  # noqa: E402
                     program_name, report_error)


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description="Run the paper's experiment (Table 1, Figures 6 and 7) with rtcl.",
        epilog="Results: -o DIR, by default a new folder rtcl-results/<study>-<date-time>, "
               "the study <device-slug> for the paper's (--accel none on the built-in "
               "scene), else <device-slug>-<accel>-<scene stem>, e.g. "
               "nvidia-h200-bvh-paper60.  Files tracked by git are never replaced: "
               "--update-committed (make results) regenerates docs/results/<study>.  See "
               "rtcl_tools/commands/experiments.py for what each file holds.")
    add_rtcl_option(parser)
    parser.add_argument("-p", "--platform", type=int, help="OpenCL platform index")
    parser.add_argument("-d", "--device", type=int, help="device index within the platform")
    parser.add_argument("-s", "--scene", metavar="FILE",
                        help="scene file (default: rtcl's built-in paper60); its stem "
                             "names the results folder, e.g. lake-10 for "
                             "tools/genbench.py lake's lake-10.json")
    parser.add_argument("--accel", choices=("none", "bvh", "bvh-compact"), default="none",
                        help="how rays find what they hit, passed to every rtcl run: "
                             "none (default) tests every object, the paper's brute force, "
                             "so Table 1 compares with the paper's; bvh traverses rtcl's "
                             "BVH, the study of divergent traversal (issue 11 item 8); "
                             "bvh-compact its compact layout (docs/bvh.md)")
    parser.add_argument("--size", help=f"image size WxH (default: the scene's; "
                                       f"{QUICK_SIZE} with --quick)")
    parser.add_argument("--depth", type=int, help="maximum ray depth (default: the scene's)")
    parser.add_argument("-r", "--repeat", type=int, default=DEFAULT_REPEAT,
                        help="timed launches per run (default %(default)s; the serial "
                             "kernel and the reference run once)")
    parser.add_argument("--quick", action="store_true",
                        help=f"--size {QUICK_SIZE} and a smaller sweep (smoke tests)")
    parser.add_argument("-o", "--out", metavar="DIR",
                        help="the folder to write into (default: a new folder "
                             "rtcl-results/<study>-<YYYYmmdd-HHMMSS>)")
    add_update_committed(parser, "docs/results/<study> of the source tree")
    parser.add_argument("--no-sweep", action="store_true", help="only the paper's geometries")
    parser.add_argument("--no-reference", action="store_true",
                        help="skip the CPU reference run")
    parser.add_argument("--no-serial", action="store_true",
                        help="skip the serial kernel (slow on a GPU: one work-item); "
                             "the table then has no speedup over serial")
    parser.add_argument("--no-plots", action="store_true",
                        help="draw no figure: write results.json and table1.md only "
                             "(as when matplotlib is missing); --replot DIR draws the "
                             "figures later from results.json, on a machine with "
                             "matplotlib")
    parser.add_argument("--peak-gflops", type=float,
                        help="the device's FP32 peak in GFLOP/s, for the bounds table "
                             "(default: NVIDIA H100/H200 and A100 from a built-in table, "
                             "a CPU from /proc/cpuinfo with --fma-units; with --replot "
                             "it replaces the stored peak)")
    parser.add_argument("--fma-units", type=int,
                        help="FMA units per CPU core, for a CPU's FP32 peak (1 for AMD "
                             "Zen 4, 2 for most Intel Xeon Gold/Platinum)")
    parser.add_argument("--replot", metavar="DIR",
                        help="run no rtcl: rewrite DIR/table1.md and the figures from "
                             "DIR/results.json with the current report code (histograms "
                             "only where results.json stores them); takes only "
                             "--no-plots, --peak-gflops, --fma-units (a CPU study's) and "
                             "--update-committed")
    parser.add_argument("--resume", metavar="DIR",
                        help="go on with the study interrupted in DIR (its results folder, "
                             f"holding {PROGRESS_NAME}) with the options it started with: "
                             "the runs it finished are not run again; takes only --rtcl")
    arguments = parser.parse_args(argv)
    given = given_options(parser, arguments)
    if arguments.resume is not None:
        others = [name for name in given if name not in ("resume", "rtcl")]
        if others:
            parser.error(f"--resume DIR goes on with the options the study started with: it "
                         f"takes no {', '.join(option_name(name) for name in others)}")
        return arguments
    if arguments.replot is not None:
        others = [name for name in given if name not in (*REPLOT_OPTIONS, "rtcl")]
        if others:
            parser.error(f"--replot DIR runs no rtcl and reads "
                         f"{', '.join(option_name(name) for name in REPLOT_OPTIONS[1:])} "
                         f"only: it takes no {', '.join(option_name(n) for n in others)}")
    if arguments.update_committed and arguments.out is not None:
        parser.error("--update-committed writes into docs/results/<study>: it takes no --out")
    if arguments.quick and arguments.size is None:
        arguments.size = QUICK_SIZE
    if arguments.repeat < 1:
        parser.error("--repeat must be at least 1")
    if arguments.peak_gflops is not None and not arguments.peak_gflops > 0:
        parser.error(f"--peak-gflops {arguments.peak_gflops:g}: expected a positive number")
    if arguments.fma_units is not None and arguments.fma_units < 1:
        parser.error(f"--fma-units {arguments.fma_units}: expected a positive integer")
    return arguments


# What --replot reads besides DIR.
REPLOT_OPTIONS = ("replot", "no_plots", "peak_gflops", "fma_units", "update_committed")


def given_options(parser, arguments):
    """Returns the names (dests) of the options given on the command line: those whose
    value is not the parser's default."""
    return [name for name, value in vars(arguments).items()
            if value != parser.get_default(name)]


def option_name(dest):
    return "--" + dest.replace("_", "-")


def output_folder(arguments, stats):
    """Returns the folder to write into, made if missing: --out, docs/results/<study>
    with --update-committed, else a new rtcl-results/<study>-<date-time>."""
    study = study_folder(stats["device"], arguments.accel, arguments.scene)
    if arguments.update_committed:
        folder = results_folder(locations.committed_results(), stats["device"],
                                arguments.accel, arguments.scene)
    elif arguments.out is not None:
        folder = pathlib.Path(arguments.out)
    else:
        return locations.new_results_folder(study)
    folder.mkdir(parents=True, exist_ok=True)
    return folder


@interruptible
def main(argv=None):
    arguments = parse_arguments(argv)
    program = program_name()
    if arguments.resume is not None:
        try:
            journal = load_journal(arguments.resume)
        except ValueError as error:
            return report_error(program, one_line(error))
        arguments = resumed_arguments(arguments, journal)
    else:
        journal = None
    with files.committed_files_allowed(arguments.update_committed):
        if arguments.replot is not None:
            return replot_main(program, arguments.replot, arguments.no_plots,
                               arguments.peak_gflops, arguments.fma_units)
        return experiment_main(program, arguments, journal)


def resumed_arguments(arguments, journal):
    """Returns the arguments of the study that journal holds (--resume): its own
    options, with --rtcl if given now, else its rtcl if it is still there."""
    options = dict(journal.options)
    rtcl = arguments.rtcl
    if rtcl is None and options.get("rtcl") and locations.is_program(options["rtcl"]):
        rtcl = options["rtcl"]
    options.pop("rtcl", None)
    return argparse.Namespace(**{**vars(arguments), **options, "rtcl": rtcl})


def experiment_main(program, arguments, journal=None):
    """Runs the experiment (or goes on with the journal's, --resume) and writes its
    results; returns the exit status.  An interrupted or failed study keeps what it
    measured in its folder's journal and says how to resume it."""
    with tempfile.TemporaryDirectory(prefix="rtcl-experiments-") as temp_name:
        temp_dir = pathlib.Path(temp_name)
        try:
            # Refused before hours of runs, not after.
            files.check_input_files([arguments.scene])
            files.reading([arguments.scene])
            if arguments.update_committed:
                locations.committed_results()
            elif arguments.out is not None and journal is None:
                files.check_output_folder(arguments.out, ("results.json", "table1.md",
                                                          PROGRESS_NAME, *FIGURES))
            arguments.rtcl = locations.find_rtcl(arguments.rtcl)
            if journal is None:
                journal = Journal(study_options(arguments),
                                  lambda stats: output_folder(arguments, stats))
            runs = run_experiment(arguments, temp_dir, journal)
            out_dir, notes = write_outputs(runs, arguments,
                                           lambda stats: journal.folder
                                           or output_folder(arguments, stats))
            journal.discard()
        except KeyboardInterrupt as error:
            print(f"\n{program}: interrupted ({signal_name(error)}); "
                  + resume_note(journal, "nothing written"), file=sys.stderr)
            return exit_status(error)
        except (RtclFailed, OSError, ValueError, FlopsFileError, locations.NotFound) as error:
            status = report_error(program, error if isinstance(error, RtclFailed)
                                  else one_line(error))
            if kept_runs(journal):
                print(f"{program}: {resume_note(journal, '')}", file=sys.stderr)
            return status
    for note in notes:
        print(f"{program}: {note}", file=sys.stderr)
    print(f"{program}: results in {out_dir}", file=sys.stderr)
    return 0


def kept_runs(journal):
    return 0 if journal is None or journal.path is None else len(journal.runs)


def resume_note(journal, otherwise):
    """Returns what an interrupted study kept and the command that goes on with it."""
    if not kept_runs(journal):
        return otherwise
    return (f"{kept_runs(journal)} run(s) kept in {journal.path}: `{command_name()} --resume "
            f"{journal.folder}` goes on with the study")


def replot_main(program, out_dir, no_plots, peak_gflops=None, fma_units=None):
    """--replot: redraws the report of out_dir; returns the exit status."""
    try:
        notes = replot(out_dir, no_plots, peak_gflops, fma_units)
    except (OSError, ValueError, locations.NotFound) as error:
        return report_error(program, one_line(error))
    for note in notes:
        print(f"{program}: {note}", file=sys.stderr)
    return 0

