"""rtcl --flops files: per-work-item flop counts, their sidecars, parallel efficiency.

`rtcl --flops FILE.npy` writes dtype '<u8', shape (global_height, global_width),
one count per launched work-item (0 for work-items given no pixel), and a
sidecar FILE.npy.json that names the kernel and geometry.  Parallel efficiency
is mean / max flops per launched work-item (docs/RENDERING.md).
"""

import dataclasses
import json
import math
import os
import pathlib

import numpy as np

from .files import open_input
from .report import one_line

FLOPS_DTYPE = np.dtype("<u8")
NPY_MAGIC = b"\x93NUMPY"
OUTPUT_FORMATS = ("png", "svg", "pdf")
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


def read_npy(path, error):
    """Returns the array of the .npy file at path (no pickles); raises error (an
    exception class) with one line naming the file when it is missing, has no
    NumPy header or cannot be read. rtcl's .npy outputs all come through here."""
    path = pathlib.Path(path)
    try:
        stream = open_input(path)
    except FileNotFoundError:
        raise error(f"{path}: no such file") from None
    except OSError as failure:
        raise error(f"{path}: {failure.strerror}") from None
    try:
        with stream:
            if stream.read(len(NPY_MAGIC)) != NPY_MAGIC:
                raise error(f"{path}: not a .npy file (no NumPy header)")
            stream.seek(0)
            return np.load(stream, allow_pickle=False)
    except (OSError, ValueError, EOFError) as failure:
        if isinstance(failure, error):
            raise
        raise error(f"{path}: not a readable .npy file ({one_line(failure)})") from None


def load_flops(path):
    """Returns the FlopsFile at path; raises FlopsFileError naming what is wrong."""
    path = pathlib.Path(path)
    counts = read_npy(path, FlopsFileError)
    if counts.dtype != FLOPS_DTYPE:
        raise FlopsFileError(f"{path}: dtype is {counts.dtype.str!r}, expected '<u8'")
    if counts.ndim != 2 or counts.size == 0:
        raise FlopsFileError(f"{path}: shape is {counts.shape}, expected a non-empty "
                             "(global_height, global_width) array")
    return FlopsFile(path, counts, _load_sidecar(path))


def _load_sidecar(npy_path):
    """Returns the sidecar's JSON object, or None when there is no sidecar."""
    path = sidecar_path(npy_path)
    if not os.path.lexists(path):
        return None
    try:
        with open_input(path, "r") as stream:
            sidecar = json.loads(stream.read())
    except OSError as error:
        raise FlopsFileError(f"{path}: unreadable sidecar ({error.strerror})") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
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


def output_format(out_path):
    """Returns 'png', 'svg' or 'pdf' from out_path's extension; ValueError otherwise."""
    extension = pathlib.Path(out_path).suffix.lower().lstrip(".")
    if extension not in OUTPUT_FORMATS:
        raise ValueError(f"{out_path}: output must end in "
                         + ", ".join("." + f for f in OUTPUT_FORMATS))
    return extension
