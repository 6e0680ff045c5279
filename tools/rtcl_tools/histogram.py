"""Figure 7's histogram of one flops file, as drawn and as stored in results.json.

The per-work-item .npy files are tens of MB each, too large to keep or to fetch
from a GPU machine; a Histogram is what the figure needs of one, in a few hundred
numbers: the bin edges (in the flop unit the axis shows) and the work-items per
bin, with the mean, max and min of the counts and the file's two-line label.
tools/experiments.py stores one per run in results.json, so that --replot
redraws the histograms exactly as the run drew them, without the .npy files.
numpy only: nothing here needs matplotlib.
"""

import dataclasses
import math

import numpy as np

from .flops import FLOP_UNITS, flop_unit

DEFAULT_BINS = 50
# The bins a stored histogram may have: results.json stays small.
MAX_STORED_BINS = 500


@dataclasses.dataclass
class Histogram:
    """Work-items per bin of flops per work-item, ready to draw."""

    label: str                 # FlopsFile.label(): kernel, geometry, efficiency
    unit: str                  # "FLOP", "kFLOP", "MFLOP" or "GFLOP": the x axis
    edges: list[float]         # bins + 1 edges, in unit
    counts: list[int]          # work-items per bin; they sum to work_items
    work_items: int
    mean: float                # of the flop counts, in FLOP
    max: int
    min: int

    @property
    def divisor(self):
        """FLOP per unit (1e3 for kFLOP)."""
        return dict((name, divisor) for divisor, name in FLOP_UNITS)[self.unit]

    def to_json(self):
        return {"label": self.label, "unit": self.unit, "bin_edges": self.edges,
                "counts": self.counts, "work_items": self.work_items, "mean": self.mean,
                "max": self.max, "min": self.min}


def bin_edges(largest_count, bins=DEFAULT_BINS):
    """Returns (edges in the unit, divisor, unit name) for counts up to largest_count:
    bins equal bins from 0 to the largest count (at least 1 FLOP)."""
    divisor, unit = flop_unit(largest_count)
    return np.linspace(0.0, max(largest_count, 1) / divisor, bins + 1), divisor, unit


def histogram_of(flops_file, bins=DEFAULT_BINS):
    """Returns the Histogram of a flops.FlopsFile: what Figure 7 draws of it."""
    counts = flops_file.counts
    largest = int(counts.max())
    edges, divisor, unit = bin_edges(largest, bins)
    per_bin, _ = np.histogram(counts.ravel() / divisor, bins=edges)
    return Histogram(flops_file.label(), unit, [float(edge) for edge in edges],
                     [int(count) for count in per_bin], int(counts.size),
                     float(counts.mean(dtype=np.float64)), largest, int(counts.min()))


def _numbers(value, kind):
    """True when value is a list of kind (int or float; int passes for float too)."""
    allowed = (int, float) if kind is float else (int,)
    return isinstance(value, list) and all(
        isinstance(item, allowed) and not isinstance(item, bool) for item in value)


def histogram_from_json(item, where):
    """Returns the Histogram stored at item; ValueError naming where if malformed."""
    if not isinstance(item, dict):
        raise ValueError(f"{where}: expected an object")
    edges, counts = item.get("bin_edges"), item.get("counts")
    units = {name for _, name in FLOP_UNITS}
    if not isinstance(item.get("label"), str) or item.get("unit") not in units:
        raise ValueError(f"{where}: expected a label and a unit among {sorted(units)}")
    if not _numbers(edges, float) or not _numbers(counts, int) or not counts \
            or len(edges) != len(counts) + 1 or len(counts) > MAX_STORED_BINS:
        raise ValueError(f"{where}: expected bin_edges (one more than counts) and "
                         f"1 ... {MAX_STORED_BINS} integer counts")
    if any(not math.isfinite(edge) for edge in edges) \
            or any(b <= a for a, b in zip(edges, edges[1:])):
        raise ValueError(f"{where}: bin_edges must increase")
    numbers = [item.get(key) for key in ("work_items", "mean", "max", "min")]
    if not _numbers(numbers, float) or not _numbers(numbers[:1] + numbers[2:], int) \
            or sum(counts) != numbers[0]:
        raise ValueError(f"{where}: expected integer work_items (the sum of counts), "
                         "max and min, and a mean")
    return Histogram(item["label"], item["unit"], [float(edge) for edge in edges],
                     list(counts), *numbers)
