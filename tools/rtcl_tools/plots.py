"""Every figure the tools draw: Figure 6 (speedups) and Figure 7 (flops per work-item).

matplotlib is imported inside the drawing functions only, so that the tools'
other parts (and every --help) work without it.
"""

import math

import numpy as np

from . import files
from .flops import flop_unit, output_format
from .report import format_number

DEFAULT_BINS = 50


def pyplot():
    """Returns matplotlib.pyplot on the Agg backend (files only, no display)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


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
    plt = pyplot()
    figure = plt.figure(figsize=size, layout="constrained")
    try:
        draw_histograms(figure, flops_files, overlay=overlay, log=log, bins=bins,
                        title=title)
        files.save_figure(figure, out_path, output_format(out_path))
    finally:
        plt.close(figure)


def plot_speedup(bars, out_path, device_name):
    """Writes Figure 6: grouped bars of speedup, ours and the paper's.

    bars: [(label, ours over serial, ours over reference, paper)], as
    table1.speedup_bars returns them.
    """
    series = (("ours, over the serial kernel", 1, "tab:blue"),
              ("ours, over the CPU reference", 2, "tab:green"),
              ("paper, over serial C on the CPU", 3, "tab:gray"))
    width = 0.8 / len(series)
    plt = pyplot()
    figure, axes = plt.subplots(figsize=(max(9, 1.2 * len(bars)), 5), layout="constrained")
    try:
        for index, (label, column, color) in enumerate(series):
            positions = [i + (index - 1) * width for i in range(len(bars))]
            values = [bar[column] or 0.0 for bar in bars]
            drawn = axes.bar(positions, values, width, label=label, color=color)
            axes.bar_label(drawn, labels=[format_number(bar[column], 0)
                                          if bar[column] else "" for bar in bars],
                           fontsize="small")
        axes.set_xticks(range(len(bars)), [bar[0] for bar in bars])
        values = [v for bar in bars for v in bar[1:] if v]
        if values and max(values) / min(values) > 100:
            axes.set_yscale("log")
        axes.set_ylabel("speedup")
        axes.set_title(f"Speedup (Figure 6): {device_name}")
        axes.legend(fontsize="small")
        files.save_figure(figure, out_path, output_format(out_path))
    finally:
        plt.close(figure)
