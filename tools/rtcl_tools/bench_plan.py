"""What tools/bench.py runs: the kernels, shapes, group counts and batches to sweep."""

import dataclasses
import math

from .paper import GROUP_KERNELS, PAPER_BATCH, PAPER_GEOMETRY
from .runner import describe, parse_pair
from . import runner

KERNELS = ("naive", "cyclic", "dynamic", "persistent", "wavefront")
KERNEL_ORDER = ("serial",) + KERNELS
WORKGROUPS = ("8x8", "16x8", "16x16", "32x4", "32x8", "8x4", "32x2")
GROUP_SCALES = (0.5, 2.0, 4.0)   # besides rtcl's default count (1x), in total groups
BATCHES = (1, 2, 4)
DEFAULT_REPEAT = 10
MIN_REPEAT = 10                  # fewer only with --quick
QUICK = {"size": "200x200", "repeat": 3, "workgroups": ("8x8", "16x8", "32x4"),
         "group_scales": (0.5, 2.0), "batches": (1, 2),
         "scaling_sizes": ("100x100", "200x200", "300x300"), "scaling_spheres": (60, 240)}


@dataclasses.dataclass
class Config:
    """One rtcl call of the benchmark: what to run and what came of it."""

    kernel: str
    workgroup: str | None = None
    groups: str | None = None          # explicit --groups; None: rtcl's default
    batch: int | None = None
    group_scale: float | None = None   # x rtcl's default count (1: the default itself)
    paper: bool = False
    stats: dict | None = None
    skipped: str | None = None         # why it did not run
    command: str = ""

    def key(self):
        """The geometry rtcl ran (or would run): kernel, work-group, groups, batch."""
        groups = self.stats["groups"] if self.stats and self.kernel in GROUP_KERNELS \
            else self.groups
        return self.kernel, self.workgroup, groups, self.batch

    def description(self):
        text = describe(self.kernel, self.workgroup, self.groups, self.batch)
        if self.group_scale == 1:
            text += " (default groups)"
        return text


def plan(kernels, workgroups, group_scales, batches, paper_only=False, serial=False):
    """Returns the Configs to run, in order: serial, then kernel by kernel."""
    configs = [Config("serial")] if serial else []
    for kernel in kernels:
        paper_workgroup, paper_groups = PAPER_GEOMETRY[kernel]
        paper_batch = PAPER_BATCH.get(kernel)
        kernel_configs = []
        if not paper_only:
            for workgroup in workgroups:
                if kernel not in GROUP_KERNELS:
                    kernel_configs.append(Config(kernel, workgroup))
                    continue
                for batch in (batches if kernel == "persistent" else (None,)):
                    for scale in (1.0, *group_scales):
                        kernel_configs.append(Config(kernel, workgroup, batch=batch,
                                                     group_scale=scale))
        match = next((c for c in kernel_configs if paper_groups is None
                      and c.workgroup == paper_workgroup and c.batch == paper_batch), None)
        if match:
            match.paper = True
        else:
            kernel_configs.append(Config(kernel, paper_workgroup, paper_groups, paper_batch,
                                         paper=True))
        configs += kernel_configs
    return configs


def scaled_groups(default_groups, scale):
    """Returns rtcl's default count 'GXxGY' scaled by scale in total (sqrt per side)."""
    return runner.scaled_groups(default_groups, math.sqrt(scale))


def groups_total(groups):
    columns, rows = parse_pair(groups)
    return columns * rows
