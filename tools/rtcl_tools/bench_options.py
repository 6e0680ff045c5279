"""rtcl-bench's (tools/bench.py's) options: defaults filled in and every one checked (UsageError)."""

import math

from .bench_plan import (BATCHES, DEFAULT_REPEAT, GROUP_SCALES, KERNELS, MIN_REPEAT, QUICK,
                         WORKGROUPS)
from .scaling import SCALING_SIZES, SCALING_SPHERES, parse_scaling_config
from .usage import (Parser, UsageError, add_rtcl_option, add_update_committed, check_pair,
                    check_positive_int, split_list)


def check_kernel(option, text):
    if text not in KERNELS:
        raise UsageError(f"{option}: unknown kernel {text!r} (choose from "
                         f"{', '.join(KERNELS)}; serial with --serial)")
    return text


def check_scale(option, text):
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (value > 0 and math.isfinite(value)) or value == 1:
        raise UsageError(f"{option}: expected positive factors other than 1 (the default "
                         f"count always runs), got {text!r}")
    return value


def parse_arguments(argv):
    parser = Parser(description="Benchmark every rtcl kernel over work-group shapes, group "
                                "counts and batches on one device (bench.csv, bench.md).",
                    epilog="Results: -o DIR, by default a new folder "
                           "rtcl-results/<device-slug>-<date-time>.  Files tracked by git "
                           "are never replaced: --update-committed (make results) "
                           "regenerates docs/results/<device-slug>.")
    add_rtcl_option(parser)
    parser.add_argument("-p", "--platform", type=int, help="OpenCL platform index")
    parser.add_argument("-d", "--device", type=int, help="device index within the platform")
    parser.add_argument("-s", "--scene", metavar="FILE", help="scene file (default: rtcl's built-in paper60)")
    parser.add_argument("--size", help="image size WxH (default: the scene's; "
                                       f"{QUICK['size']} with --quick)")
    parser.add_argument("--depth", type=int, help="maximum ray depth (default: the scene's)")
    parser.add_argument("-r", "--repeat", type=int,
                        help=f"timed launches per configuration (default {DEFAULT_REPEAT}; "
                             f"at least {MIN_REPEAT} unless --quick, whose default is "
                             f"{QUICK['repeat']})")
    parser.add_argument("--quick", action="store_true",
                        help=f"a smoke run: --size {QUICK['size']}, a smaller sweep, fewer "
                             "launches allowed, small scaling sizes")
    parser.add_argument("-o", "--out", metavar="DIR",
                        help="the folder to write into (default: a new folder "
                             "rtcl-results/<device-slug>-<YYYYmmdd-HHMMSS>)")
    add_update_committed(parser, "docs/results/<device-slug> of the source tree")
    parser.add_argument("--kernels", help=f"comma-separated (default {','.join(KERNELS)})")
    parser.add_argument("--workgroups", help=f"work-group shapes (default "
                                             f"{','.join(WORKGROUPS)})")
    parser.add_argument("--group-scales", help="total group counts to try besides rtcl's "
                                               "default, as factors of it (default "
                                               f"{','.join(f'{s:g}' for s in GROUP_SCALES)})")
    parser.add_argument("--batches", help="--batch values of the persistent kernel (default "
                                          f"{','.join(map(str, BATCHES))})")
    parser.add_argument("--paper-only", action="store_true",
                        help="only the paper's geometries (and persistent's and wavefront's "
                             "nearest)")
    parser.add_argument("--serial", action="store_true",
                        help="also the serial kernel (one work-item: ~1000x slower; one "
                             "timed launch)")
    parser.add_argument("--no-sweep", action="store_true",
                        help="no sweep (with --scaling: only the scaling runs)")
    parser.add_argument("--peak-gflops", type=float,
                        help="the device's FP32 peak in GFLOP/s (without it, and where "
                             "the peak is not known, the %% of peak column stays empty)")
    parser.add_argument("--fma-units", type=int,
                        help="FMA units per CPU core, for a CPU's FP32 peak")
    parser.add_argument("--scaling", action="store_true",
                        help="also time one configuration at several sizes and sphere "
                             "counts (scaling.csv, scaling.md)")
    parser.add_argument("--scaling-config", metavar="KERNEL[:WxH[:GROUPS[:BATCH]]]",
                        help="the configuration of the scaling runs (default: the sweep's "
                             "fastest, else dynamic:8x8)")
    parser.add_argument("--scaling-sizes", help="image sizes (default "
                                                f"{','.join(SCALING_SIZES)})")
    parser.add_argument("--scaling-spheres", help="sphere counts (default "
                                                  f"{','.join(map(str, SCALING_SPHERES))})")
    arguments = parser.parse_args(argv)
    return check_arguments(arguments)


def check_arguments(a):
    """Fills in defaults and checks the options; raises UsageError."""
    a.kernels = split_list("--kernels", a.kernels, check_kernel) if a.kernels else KERNELS
    given = [name for name, value in (("--workgroups", a.workgroups),
                                      ("--group-scales", a.group_scales),
                                      ("--batches", a.batches)) if value]
    if a.paper_only and given:
        raise UsageError(f"--paper-only runs the paper's geometries only: it takes no "
                         f"{', '.join(given)}")
    a.workgroups = (split_list("--workgroups", a.workgroups, check_pair) if a.workgroups
                    else QUICK["workgroups"] if a.quick else WORKGROUPS)
    a.group_scales = (split_list("--group-scales", a.group_scales, check_scale)
                      if a.group_scales else QUICK["group_scales"] if a.quick
                      else GROUP_SCALES)
    a.batches = (split_list("--batches", a.batches, check_positive_int) if a.batches
                 else QUICK["batches"] if a.quick else BATCHES)
    if any(batch > 4096 for batch in a.batches):
        raise UsageError("--batches: rtcl takes --batch up to 4096")
    a.scaling_sizes = (split_list("--scaling-sizes", a.scaling_sizes, check_pair)
                       if a.scaling_sizes else QUICK["scaling_sizes"] if a.quick
                       else SCALING_SIZES)
    a.scaling_spheres = (split_list("--scaling-spheres", a.scaling_spheres,
                                    check_positive_int) if a.scaling_spheres
                         else QUICK["scaling_spheres"] if a.quick else SCALING_SPHERES)
    if a.scaling_config:
        parse_scaling_config(a.scaling_config)
    if a.repeat is None:
        a.repeat = QUICK["repeat"] if a.quick else DEFAULT_REPEAT
    if a.repeat < 1:
        raise UsageError("--repeat must be at least 1")
    if a.repeat < MIN_REPEAT and not a.quick:
        raise UsageError(f"--repeat {a.repeat}: a benchmark takes the median of at least "
                         f"{MIN_REPEAT} launches (fewer only with --quick)")
    if a.size is not None:
        check_pair("--size", a.size)
    elif a.quick:
        a.size = QUICK["size"]
    if a.depth is not None and not 0 <= a.depth <= 64:
        raise UsageError(f"--depth {a.depth}: expected 0 ... 64")
    if a.peak_gflops is not None and not (a.peak_gflops > 0 and math.isfinite(a.peak_gflops)):
        raise UsageError(f"--peak-gflops {a.peak_gflops:g}: expected a positive number")
    if a.fma_units is not None and a.fma_units < 1:
        raise UsageError(f"--fma-units {a.fma_units}: expected a positive integer")
    if a.update_committed and a.out is not None:
        raise UsageError("--update-committed writes into docs/results/<device-slug>: it "
                         "takes no --out")
    if a.no_sweep and not a.scaling:
        raise UsageError("--no-sweep without --scaling leaves nothing to run")
    if a.no_sweep and (a.paper_only or a.serial):
        raise UsageError("--no-sweep contradicts --paper-only and --serial")
    return a
