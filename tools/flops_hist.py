#!/usr/bin/env python3
"""Plot the distribution of flops per work-item: Figure 7 of the 2009 paper.

Reads the per-work-item flop counts that `rtcl --flops FILE.npy` writes (dtype
'<u8', shape (global_height, global_width), one count per launched work-item,
0 for work-items given no pixel) and, when present, the sidecar FILE.npy.json
that names the kernel and geometry.  Each file gets one histogram (or one curve
of a shared plot with --overlay) titled with its kernel, work-group shape, group
count and parallel efficiency = mean / max flops per launched work-item
(docs/RENDERING.md), computed from the counts and cross-checked against the
sidecar.

    tools/flops_hist.py naive.npy cyclic.npy dynamic.npy -o fig7.png --log
    tools/flops_hist.py run.npy --overlay --bins 100 -o run.svg

A file that is missing, unreadable or not a 2-D '<u8' array is an error: one line
on stderr, exit status 1, and no output file.  The output is written to a
temporary file and renamed, so it is never left half-written.
"""

import argparse
import dataclasses
import json
import math
import os
import pathlib
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (the backend must be chosen first)
import numpy as np  # noqa: E402

FLOPS_DTYPE = np.dtype("<u8")
NPY_MAGIC = b"\x93NUMPY"
OUTPUT_FORMATS = ("png", "svg", "pdf")
DEFAULT_BINS = 50
# Sidecar and data may disagree by float rounding of the mean, no more.
EFFICIENCY_TOLERANCE = 1e-6
# How a multi-launch kernel's sidecar (rtcl's wavefront) starts its "layout":
# counts[0][i] over every launch's work-items, so global_size, which is the
# primary-ray launch's, is not the array's shape.
MULTI_PASS_LAYOUT = "counts[0][i]"
# (divisor, name) for the x axis, largest first.
FLOP_UNITS = ((1e9, "GFLOP"), (1e6, "MFLOP"), (1e3, "kFLOP"), (1.0, "FLOP"))


class FlopsFileError(Exception):
    """A flops file (or its sidecar) that cannot be used; the message names it."""


@dataclasses.dataclass
class FlopsFile:
    """The counts of one `rtcl --flops` file and what its sidecar says about them."""

    path: pathlib.Path
    counts: np.ndarray          # shape (global_height, global_width), dtype '<u8'
    sidecar: dict | None        # the FILE.npy.json contents, None when absent

    @property
    def efficiency(self):
        return parallel_efficiency(self.counts)

    @property
    def kernel(self):
        return (self.sidecar or {}).get("kernel") or self.path.stem

    @property
    def multi_pass(self):
        """True for a kernel of several launches (the wavefront): the counts are
        one row, every launch's work-items one after the other."""
        layout = (self.sidecar or {}).get("layout")
        return isinstance(layout, str) and layout.startswith(MULTI_PASS_LAYOUT)

    def geometry(self):
        """Returns e.g. 'work-group 8x8, groups 25x25, 200x200 work-items'."""
        height, width = self.counts.shape
        items = f"{width}x{height} work-items"
        if not self.sidecar:
            return items
        workgroup = _shape_text(self.sidecar.get("workgroup"))
        groups = _shape_text(self.sidecar.get("groups"))
        if self.multi_pass:
            return (f"{self.counts.size} work-items of all launches\n(primary rays: "
                    f"work-group {workgroup}, groups {groups}; then one per bounce)")
        return f"work-group {workgroup}, groups {groups}, {items}"

    def label(self):
        """Two lines for a title or legend: kernel and geometry, then efficiency."""
        scope = " over all launches" if self.multi_pass else ""
        return (f"{self.kernel}: {self.geometry()}\n"
                f"parallel efficiency{scope} {format_efficiency(self.efficiency)}")


def _shape_text(value):
    """Returns [8, 8] or "8x8" as '8x8', anything else as '?'."""
    if isinstance(value, (list, tuple)) and len(value) == 2:
        return f"{value[0]}x{value[1]}"
    return str(value) if value else "?"


def parallel_efficiency(counts):
    """Returns mean / max of the flop counts over all launched work-items.

    Work-items given no pixel count as 0 and so lower the mean.  Returns NaN when
    no work-item did any work (the ratio is undefined); raises ValueError for an
    empty array.
    """
    counts = np.asarray(counts)
    if counts.size == 0:
        raise ValueError("no work-items: cannot compute parallel efficiency")
    peak = counts.max()
    if peak == 0:
        return math.nan
    # float64 sum: exact enough for 2^53 total flops, and no uint64 overflow.
    return float(counts.sum(dtype=np.float64) / counts.size / float(peak))


def format_efficiency(efficiency):
    """Returns 0.7744 as '77.44%', NaN as 'n/a'."""
    return "n/a" if math.isnan(efficiency) else f"{100 * efficiency:.2f}%"


def sidecar_path(npy_path):
    """Returns the sidecar's path: the .npy path with '.json' appended."""
    npy_path = pathlib.Path(npy_path)
    return npy_path.with_name(npy_path.name + ".json")


def load_flops(path):
    """Returns the FlopsFile at path; raises FlopsFileError naming what is wrong."""
    path = pathlib.Path(path)
    if not path.is_file():
        raise FlopsFileError(f"{path}: no such file")
    try:
        with open(path, "rb") as stream:
            if stream.read(len(NPY_MAGIC)) != NPY_MAGIC:
                raise FlopsFileError(f"{path}: not a .npy file (no NumPy header)")
        counts = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as error:
        raise FlopsFileError(f"{path}: not a readable .npy file ({error})") from None
    if counts.dtype != FLOPS_DTYPE:
        raise FlopsFileError(f"{path}: dtype is {counts.dtype.str!r}, expected '<u8'")
    if counts.ndim != 2 or counts.size == 0:
        raise FlopsFileError(f"{path}: shape is {counts.shape}, expected a non-empty "
                             "(global_height, global_width) array")
    return FlopsFile(path, counts, _load_sidecar(path))


def _load_sidecar(npy_path):
    """Returns the sidecar's JSON object, or None when there is no sidecar."""
    path = sidecar_path(npy_path)
    if not path.exists():
        return None
    try:
        sidecar = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise FlopsFileError(f"{path}: unreadable sidecar ({error})") from None
    if not isinstance(sidecar, dict):
        raise FlopsFileError(f"{path}: sidecar is not a JSON object")
    return sidecar


def sidecar_mismatches(flops_file):
    """Returns one message per figure where the sidecar disagrees with the counts."""
    sidecar = flops_file.sidecar
    if not sidecar:
        return []
    counts = flops_file.counts
    problems = []
    global_size = sidecar.get("global_size")
    if flops_file.multi_pass:
        if counts.shape[0] != 1:
            problems.append(f"layout says one row of launches but the array has "
                            f"{counts.shape[0]} rows")
        elif global_size is not None and len(global_size) == 2 \
                and counts.shape[1] < global_size[0] * global_size[1]:
            problems.append(f"global_size {global_size} (the first launch) but the array "
                            f"has only {counts.shape[1]} work-items")
    elif global_size is not None and list(global_size) != [counts.shape[1], counts.shape[0]]:
        problems.append(f"global_size {global_size} but the array is "
                        f"{counts.shape[1]}x{counts.shape[0]}")
    total = sidecar.get("total_flops")
    if total is not None and int(total) != int(counts.sum(dtype=np.uint64)):
        problems.append(f"total_flops {total} but the counts sum to "
                        f"{int(counts.sum(dtype=np.uint64))}")
    claimed = sidecar.get("parallel_efficiency")
    computed = flops_file.efficiency
    if claimed is not None and not math.isnan(computed) \
            and abs(float(claimed) - computed) > EFFICIENCY_TOLERANCE:
        problems.append(f"parallel_efficiency {claimed} but the counts give {computed:.6f}")
    return problems


def flop_unit(largest_count):
    """Returns (divisor, name) of the unit that shows largest_count as 1..999."""
    for divisor, name in FLOP_UNITS:
        if largest_count >= divisor:
            return divisor, name
    return FLOP_UNITS[-1]


def draw_histograms(figure, flops_files, *, overlay=False, log=False,
                    bins=DEFAULT_BINS, title=None):
    """Draws one histogram per file onto figure, or all on one axes with overlay.

    Each subplot gets its own range and flop unit: the paper-geometry kernels give
    their work-items 1 to ~100 pixels each, so a shared axis would flatten some of
    them into one bar.  Overlaid histograms share the unit and the bin edges.
    """
    if overlay:
        axes = figure.add_subplot(1, 1, 1)
        _draw_overlay(axes, flops_files, bins)
        axes_list = [axes]
    else:
        columns = min(len(flops_files), 3)
        rows = math.ceil(len(flops_files) / columns)
        axes_list = [figure.add_subplot(rows, columns, i + 1)
                     for i in range(len(flops_files))]
        for axes, flops_file in zip(axes_list, flops_files):
            _draw_one(axes, flops_file, bins)
    for axes in axes_list:
        axes.set_ylabel("work-items")
        if log:
            axes.set_yscale("log")
        axes.legend(fontsize="small")
    if title:
        figure.suptitle(title)


def _bin_edges(largest_count, bins):
    """Returns (edges in the unit, divisor, unit name) for counts up to largest_count."""
    divisor, unit = flop_unit(largest_count)
    return np.linspace(0.0, max(largest_count, 1) / divisor, bins + 1), divisor, unit


def _draw_one(axes, flops_file, bins):
    """Draws one file's histogram with dashed mean and dotted max markers."""
    edges, divisor, unit = _bin_edges(int(flops_file.counts.max()), bins)
    values = flops_file.counts.ravel() / divisor
    axes.hist(values, bins=edges, color="tab:blue")
    axes.axvline(values.mean(), color="tab:orange", linestyle="--", label="mean")
    axes.axvline(values.max(), color="tab:red", linestyle=":", label="max")
    axes.set_title(flops_file.label(), fontsize="medium")
    axes.set_xlabel(f"flops per work-item ({unit})")


def _draw_overlay(axes, flops_files, bins):
    """Draws every file's histogram as an outline over shared bins."""
    largest = max(int(flops_file.counts.max()) for flops_file in flops_files)
    edges, divisor, unit = _bin_edges(largest, bins)
    for flops_file in flops_files:
        axes.hist(flops_file.counts.ravel() / divisor, bins=edges, histtype="step",
                  linewidth=1.5, label=flops_file.label())
    axes.set_xlabel(f"flops per work-item ({unit})")


def save_figure_atomically(figure, out_path):
    """Saves figure to out_path through a temporary file in the same folder."""
    out_path = pathlib.Path(out_path)
    file_format = output_format(out_path)
    descriptor, temporary = tempfile.mkstemp(dir=out_path.parent or ".",
                                             prefix=f".{out_path.name}.", suffix=".tmp")
    try:
        with os.fdopen(descriptor, "wb") as stream:
            figure.savefig(stream, format=file_format, dpi=120)
        os.chmod(temporary, 0o666 & ~current_umask())
        os.replace(temporary, out_path)
    except BaseException:
        os.unlink(temporary)
        raise


def current_umask():
    """Returns the process's umask (mkstemp creates files 0600; outputs should not be)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


def output_format(out_path):
    """Returns 'png', 'svg' or 'pdf' from out_path's extension; ValueError otherwise."""
    extension = pathlib.Path(out_path).suffix.lower().lstrip(".")
    if extension not in OUTPUT_FORMATS:
        raise ValueError(f"{out_path}: output must end in "
                         + ", ".join("." + f for f in OUTPUT_FORMATS))
    return extension


def plot_flops_histograms(flops_files, out_path, *, overlay=False, log=False,
                          bins=DEFAULT_BINS, title=None):
    """Plots the histograms of flops_files (FlopsFile list) into out_path."""
    output_format(out_path)  # fail before drawing anything
    count = len(flops_files)
    if overlay:
        size = (9, 5)
    else:
        columns = min(count, 3)
        size = (6 * columns, 4.5 * math.ceil(count / columns))
    figure = plt.figure(figsize=size, layout="constrained")
    try:
        draw_histograms(figure, flops_files, overlay=overlay, log=log, bins=bins,
                        title=title)
        save_figure_atomically(figure, out_path)
    finally:
        plt.close(figure)


def one_line(error):
    """Returns the message of error on one line (numpy's may span several)."""
    return " ".join(str(error).split())


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description="Plot the distribution of flops per work-item (the paper's "
                    "Figure 7) from rtcl --flops files.")
    parser.add_argument("files", nargs="+", metavar="FILE.npy",
                        help="per-work-item flop counts written by rtcl --flops")
    parser.add_argument("-o", "--output", default="flops_hist.png",
                        help="image to write: .png, .svg or .pdf (default %(default)s)")
    parser.add_argument("--log", action="store_true", help="log-scale work-item counts")
    parser.add_argument("--overlay", action="store_true",
                        help="draw every file on one plot instead of one subplot each")
    parser.add_argument("--bins", type=int, default=DEFAULT_BINS,
                        help="histogram bins (default %(default)s)")
    parser.add_argument("--title", help="title over the whole figure")
    arguments = parser.parse_args(argv)
    if arguments.bins < 1:
        parser.error("--bins must be at least 1")
    return arguments


def main(argv=None):
    arguments = parse_arguments(argv)
    program = pathlib.Path(sys.argv[0]).name
    try:
        output_format(arguments.output)
        flops_files = [load_flops(path) for path in arguments.files]
        for flops_file in flops_files:
            for problem in sidecar_mismatches(flops_file):
                print(f"{program}: warning: {sidecar_path(flops_file.path)}: {problem}",
                      file=sys.stderr)
        plot_flops_histograms(flops_files, arguments.output, overlay=arguments.overlay,
                              log=arguments.log, bins=arguments.bins,
                              title=arguments.title)
    except (FlopsFileError, ValueError, OSError) as error:
        print(f"{program}: error: {one_line(error)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
