"""Plot the distribution of flops per work-item: Figure 7 of the 2009 paper.

Reads the per-work-item flop counts that `rtcl --flops FILE.npy` writes (dtype
'<u8', shape (global_height, global_width), one count per launched work-item,
0 for work-items given no pixel) and, when present, the sidecar FILE.npy.json
that names the kernel and geometry.  Each file gets one histogram (or one curve
of a shared plot with --overlay), all in one flop unit, titled with its kernel,
work-group shape, group count and parallel efficiency = mean / max flops per
launched work-item (docs/RENDERING.md), computed from the counts and
cross-checked against the sidecar.  With several files the y axis is the % of each file's work-items
(--counts: the counts themselves), since kernels launch different numbers of them.

    rtcl-flops-hist naive.npy cyclic.npy dynamic.npy -o fig7.png --log
    rtcl-flops-hist run.npy --overlay --bins 100 -o run.svg

A file that is missing, unreadable, not a regular file (a folder, a FIFO) or not a
2-D '<u8' array is an error: one line on stderr, exit status 1, and no output file;
so is an output file tracked by git (unless --update-committed) or one that names an
input (a flops file or its sidecar, by path, link or inode); --bins above 1000 is
refused.  The output is written to a temporary file and renamed, so it is never
left half-written.  Needs numpy and matplotlib.
"""

import argparse
import sys

from ..requirements import require

require("numpy")  # the flops files; matplotlib once the options are read (--help needs none)

from .. import files  # noqa: E402
from ..flops import (FlopsFileError, load_flops, output_format,  # noqa: E402
                     sidecar_mismatches, sidecar_path)
from ..interrupts import interruptible  # noqa: E402
from ..plots import DEFAULT_BINS, plot_flops_histograms  # noqa: E402
from ..report import one_line  # noqa: E402
from ..usage import add_update_committed, program_name, report_error  # noqa: E402

# More bins than a figure has pixel columns show nothing more (1000 draw in about
# a second here, 10000 in 8 s; 10^8 drew for hours).
MAX_BINS = 1000


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description="Plot the distribution of flops per work-item (the paper's "
                    "Figure 7) from rtcl --flops files.")
    parser.add_argument("files", nargs="+", metavar="FILE.npy",
                        help="per-work-item flop counts written by rtcl --flops")
    parser.add_argument("-o", "--output", "--out", default="flops_hist.png",
                        help="image to write: .png, .svg or .pdf (default %(default)s)")
    parser.add_argument("--log", action="store_true", help="log-scale work-item counts")
    parser.add_argument("--counts", action="store_true",
                        help="draw work-item counts on the y axis; by default, with "
                             "several files, each bar is a %% of its file's work-items "
                             "(kernels launch different numbers of them)")
    parser.add_argument("--overlay", action="store_true",
                        help="draw every file on one plot instead of one subplot each")
    parser.add_argument("--bins", type=int, default=DEFAULT_BINS,
                        help=f"histogram bins, 1 ... {MAX_BINS} (default %(default)s)")
    parser.add_argument("--title", help="title over the whole figure")
    add_update_committed(parser)
    arguments = parser.parse_args(argv)
    if not 1 <= arguments.bins <= MAX_BINS:
        parser.error(f"--bins {arguments.bins}: expected 1 ... {MAX_BINS} (a figure is "
                     "about a thousand pixels wide: more bins draw nothing more, and "
                     "millions take hours)")
    return arguments


@interruptible
def main(argv=None):
    arguments = parse_arguments(argv)
    program = program_name()
    require("matplotlib")
    try:
        with files.committed_files_allowed(arguments.update_committed):
            draw(program, arguments)
    except (FlopsFileError, ValueError, OSError) as error:
        return report_error(program, one_line(error))
    return 0


def draw(program, arguments):
    """Reads the flops files and writes the figure."""
    output_format(arguments.output)
    files.reading([*arguments.files, *map(sidecar_path, arguments.files)])
    files.check_outputs([arguments.output])
    flops_files = [load_flops(path) for path in arguments.files]
    for flops_file in flops_files:
        for problem in sidecar_mismatches(flops_file):
            print(f"{program}: warning: {sidecar_path(flops_file.path)}: {problem}",
                  file=sys.stderr)
    plot_flops_histograms(flops_files, arguments.output, overlay=arguments.overlay,
                          log=arguments.log, bins=arguments.bins, title=arguments.title,
                          share=False if arguments.counts else None)
