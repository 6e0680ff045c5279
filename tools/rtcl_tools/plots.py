"""Every figure the tools draw: Figure 6 (speedups) and Figure 7 (flops per work-item).

matplotlib is imported inside the drawing functions only, so that the tools'
other parts (and every --help) work without it.
"""

import math

from . import files
from .flops import flop_unit, output_format
from .histogram import DEFAULT_BINS, Histogram, bin_edges, histogram_of
from .report import format_number


def matplotlib_missing():
    """Returns why matplotlib cannot be imported (one line), or None when it can."""
    try:
        import matplotlib  # noqa: F401
    except ImportError as error:
        return str(error) or "no module named 'matplotlib'"
    return None


def pyplot():
    """Returns matplotlib.pyplot on the Agg backend (files only, no display)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def draw_histograms(figure, flops_files, *, overlay=False, log=False,
                    bins=DEFAULT_BINS, title=None, share=None):
    """Draws one histogram per file onto figure, or all on one axes with overlay.

    flops_files: flops.FlopsFile objects, or (without overlay) histogram.Histogram
    objects, as results.json stores them.  One flop unit for the whole figure (the
    one that shows the smallest subplot's largest count as 1 to 999), each subplot
    over its own range: the paper-geometry kernels give their work-items 1 to ~100 pixels each, so a shared range would
    flatten some of them into one bar.  share: the y axis in % of each file's
    work-items, so that kernels of different work-item counts compare; by default
    when several files share the figure.  Overlaid histograms share the bin edges.
    """
    if share is None:
        share = len(flops_files) > 1
    histograms = [item if isinstance(item, Histogram) else histogram_of(item, bins)
                  for item in flops_files] if not overlay else None
    if overlay:
        axes = figure.add_subplot(1, 1, 1)
        _draw_overlay(axes, flops_files, bins, share)
        axes_list = [axes]
    else:
        # The unit that shows the smallest subplot's largest count as 1..999: no
        # subplot reads 0.0001; the largest read with thousands separators.
        divisor, unit = flop_unit(min(histogram.max for histogram in histograms))
        columns = min(len(histograms), 3)
        rows = math.ceil(len(histograms) / columns)
        axes_list = [figure.add_subplot(rows, columns, i + 1)
                     for i in range(len(histograms))]
        for axes, histogram in zip(axes_list, histograms):
            _draw_one(axes, histogram, divisor, unit, share)
    for axes in axes_list:
        axes.set_ylabel("% of work-items" if share else "work-items")
        if log:
            axes.set_yscale("log")
        axes.legend(fontsize="small")
    if title:
        figure.suptitle(title)


def _draw_one(axes, histogram, divisor, unit, share):
    """Draws one Histogram in unit (divisor FLOP each) with dashed mean and dotted max
    markers; share: each bar as a % of the histogram's work-items.

    Each bin's count is drawn as the weight of its left edge: the same bars that
    axes.hist of the per-work-item values over these edges draws.
    """
    edges = [edge * histogram.divisor / divisor for edge in histogram.edges]
    scale = 100.0 / histogram.work_items if share and histogram.work_items else 1.0
    axes.hist(edges[:-1], bins=edges, weights=[count * scale for count in histogram.counts],
              color="tab:blue")
    axes.axvline(histogram.mean / divisor, color="tab:orange", linestyle="--", label="mean")
    axes.axvline(histogram.max / divisor, color="tab:red", linestyle=":", label="max")
    axes.set_title(histogram.label, fontsize="medium")
    axes.set_xlabel(f"flops per work-item ({unit})")
    from matplotlib.ticker import FuncFormatter, MaxNLocator
    axes.xaxis.set_major_locator(MaxNLocator(5))
    axes.xaxis.set_major_formatter(FuncFormatter(tick_label))


def tick_label(value, _position=None):
    """Returns an axis tick's label: thousands separated from 10 on, else 3 digits."""
    return f"{value:,.0f}" if abs(value) >= 10 else f"{value:.3g}"


def _draw_overlay(axes, flops_files, bins, share):
    """Draws every file's histogram as an outline over shared bins."""
    largest = max(int(flops_file.counts.max()) for flops_file in flops_files)
    edges, divisor, unit = bin_edges(largest, bins)
    for flops_file in flops_files:
        values = flops_file.counts.ravel()
        weights = None
        if share:
            import numpy
            weights = numpy.full(values.size, 100.0 / values.size)
        axes.hist(values / divisor, bins=edges, weights=weights, histtype="step",
                  linewidth=1.5, label=flops_file.label())
    axes.set_xlabel(f"flops per work-item ({unit})")


def plot_flops_histograms(flops_files, out_path, *, overlay=False, log=False,
                          bins=DEFAULT_BINS, title=None, share=None):
    """Plots the histograms of flops_files (FlopsFile or Histogram list) into out_path."""
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
                        title=title, share=share)
        files.save_figure(figure, out_path, output_format(out_path))
    finally:
        plt.close(figure)


# Figure 6's panels: (title, column of table1.speedup_bars, colour).  Each speedup
# has its own baseline, so each gets its own axes: the paper's serial is a CPU
# program on its 2009 server, ours a single work-item on the device measured.
SPEEDUP_PANELS = (("rtcl over one work-item on this device\n(the serial kernel)",
                   1, "tab:blue"),
                  ("rtcl over its CPU reference\n(C++, one core)", 2, "tab:green"),
                  ("the paper over its CPU program\n(serial C, Lincoln, 2009)",
                   3, "tab:gray"))


def speedup_limits(values):
    """Returns (bottom, top) of a log speedup axis: from 1 (no speedup) past the top.

    A bar below 1 (slower than the baseline) moves the bottom to the power of ten
    under it, so that the bar still shows.
    """
    bottom = min(1.0, 10.0 ** math.floor(math.log10(min(values))))
    return bottom, max(values) * 3.0   # room above the tallest bar for its label


def draw_speedup(figure, bars, device_name):
    """Draws Figure 6 onto figure, one panel per baseline; returns the axes drawn.

    bars: [(label, ours over serial, ours over reference, paper)], as
    table1.speedup_bars returns them.  A panel shows only the bars it has a value
    for and is left out when it has none (no serial run, say).  Bars rise from 1.
    """
    panels = []
    for title, column, color in SPEEDUP_PANELS:
        shown = [(bar[0], bar[column]) for bar in bars if bar[column]]
        if shown:
            panels.append((title, color, shown))
    figure.suptitle(f"Speedup (Figure 6): {device_name}")
    if not panels:
        axes = figure.add_subplot(1, 1, 1)
        axes.text(0.5, 0.5, "no speedup measured", ha="center", va="center")
        axes.set_axis_off()
        return [axes]
    grid = figure.add_gridspec(1, len(panels),
                               width_ratios=[max(3, len(shown)) for _, _, shown in panels])
    axes_list = []
    for index, (title, color, shown) in enumerate(panels):
        axes = figure.add_subplot(grid[0, index])
        values = [value for _, value in shown]
        drawn = axes.bar(range(len(shown)), [value - 1.0 for value in values], 0.6,
                         bottom=1.0, color=color)
        axes.bar_label(drawn, labels=[format_number(value, 0 if value >= 10 else 1)
                                      for value in values], fontsize="small")
        axes.set_xticks(range(len(shown)), [label for label, _ in shown], fontsize="small")
        axes.set_yscale("log")
        bottom, top = speedup_limits(values)
        axes.set_ylim(bottom, top)
        _plain_log_labels(axes.yaxis, minor=top / bottom < 20)
        axes.set_ylabel("speedup")
        axes.set_title(title, fontsize="medium")
        axes_list.append(axes)
    return axes_list


def _plain_log_labels(axis, minor):
    """Labels a log axis 0.1, 1, 10, 1,000 (not 10^3); its minor ticks too if minor."""
    from matplotlib import ticker
    plain = ticker.FuncFormatter(lambda value, _: format_number(value, 0 if value >= 1
                                                                else 1))
    axis.set_major_formatter(plain)
    axis.set_minor_formatter(plain if minor else ticker.NullFormatter())


def plot_speedup(bars, out_path, device_name):
    """Writes Figure 6 (draw_speedup) into out_path."""
    output_format(out_path)  # fail before drawing anything
    counts = [sum(1 for bar in bars if bar[column]) for _, column, _ in SPEEDUP_PANELS]
    width = max(9, 0.75 * sum(max(3, count) for count in counts if count) + 2)
    plt = pyplot()
    figure = plt.figure(figsize=(width, 5), layout="constrained")
    try:
        draw_speedup(figure, bars, device_name)
        files.save_figure(figure, out_path, output_format(out_path))
    finally:
        plt.close(figure)
