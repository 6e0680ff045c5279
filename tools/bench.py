#!/usr/bin/env python3
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

Under OUT/<device-slug>/ it writes
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
has finished: a failed or interrupted benchmark writes nothing.

The FP32 peak: NVIDIA H100 / H200 (GH100) from a built-in table, SMs (rtcl's
compute units) x 128 FP32 lanes x 2 (FMA) x boost clock; a CPU under PoCL as
physical cores x SIMD lanes (from /proc/cpuinfo: avx512f 16, avx2+fma 8) x FMA
units per core (--fma-units: the flags do not tell) x 2 x clock (rtcl's
max_clock_mhz); anything else needs --peak-gflops.

    tools/bench.py -p 0 -d 0 --fma-units 1            # the full sweep, 2000x2000
    tools/bench.py --paper-only --peak-gflops 100      # the paper's geometries only
    tools/bench.py --quick --scaling --fma-units 1    # a smoke run of a few minutes
    make bench DEVICE="-p 0 -d 0" BENCH="--scaling"
"""

import argparse
import csv
import dataclasses
import datetime
import io
import math
import os
import pathlib
import re
import shlex
import shutil
import subprocess
import sys
import tempfile

TOOLS = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(TOOLS))
import experiments  # noqa: E402  (found through the line above)
from experiments import RtclFailed, describe, parse_pair  # noqa: E402

KERNELS = ("naive", "cyclic", "dynamic", "persistent", "wavefront")
KERNEL_ORDER = ("serial",) + KERNELS
GROUP_KERNELS = experiments.GROUP_KERNELS
WORKGROUPS = ("8x8", "16x8", "16x16", "32x4", "32x8", "8x4", "32x2")
GROUP_SCALES = (0.5, 2.0, 4.0)   # besides rtcl's default count (1x), in total groups
BATCHES = (1, 2, 4)
DEFAULT_REPEAT = 10
MIN_REPEAT = 10                  # fewer only with --quick
QUICK = {"size": "200x200", "repeat": 3, "workgroups": ("8x8", "16x8", "32x4"),
         "group_scales": (0.5, 2.0), "batches": (1, 2),
         "scaling_sizes": ("100x100", "200x200", "300x300"), "scaling_spheres": (60, 240)}
SCALING_SIZES = ("500x500", "1000x1000", "2000x2000", "3000x3000", "4000x4000")
SCALING_SPHERES = (60, 240, 600)
SCALING_SEED = 2009
SCALING_DEFAULT = ("dynamic", "8x8", None, None)   # kernel, work-group, groups, batch

# GPUs whose FP32 peak is known: (pattern on the device name, part, FP32 lanes per
# compute unit, boost clock in GHz).  Matched in order: the first that matches.
GPU_PEAKS = (
    (r"H100.*PCIe", "NVIDIA H100 PCIe (GH100)", 128, 1.755),
    (r"H100.*NVL", "NVIDIA H100 NVL (GH100)", 128, 1.785),
    (r"H200.*NVL", None, None, None),               # its clock: not in the table
    (r"\bH100\b|\bH200\b", "NVIDIA H100/H200 SXM (GH100)", 128, 1.98),
    (r"\bA100\b", "NVIDIA A100 (GA100)", 64, 1.41),
)

CSV_COLUMNS = ("kernel", "workgroup", "groups", "groups_total", "group_scale", "batch",
               "paper", "status", "reason", "median_ms", "min_ms", "max_ms", "repeat",
               "kernel_ms_all", "mrays_per_s", "gflops", "peak_percent",
               "parallel_efficiency", "gflop", "total_flops", "rays", "rays_per_pixel",
               "flops_per_item_mean", "flops_per_item_max", "flops_per_item_min",
               "global_size", "width", "height", "max_depth", "scene",
               "scene_in_local_memory", "build_options", "command")
TABLE_COLUMNS = ("kernel", "work-group", "groups", "batch", "median ms", "min ms", "max ms",
                 "Mrays/s", "GFLOP/s", "% of FP32 peak", "parallel efficiency",
                 "total GFLOP", "rays/pixel", "note")
SCALING_COLUMNS = ("spheres", "width", "height", "megapixels", "status", "reason",
                   "median_ms", "min_ms", "max_ms", "ms_per_megapixel",
                   "ms_per_megapixel_sphere", "gflop", "gflops", "mrays_per_s",
                   "rays_per_pixel", "parallel_efficiency", "repeat", "kernel_ms_all",
                   "scene", "command")


class UsageError(Exception):
    """A bad option, or one that is missing (exit status 2)."""


# ---- configurations -------------------------------------------------------------

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
        paper_workgroup, paper_groups = experiments.PAPER_GEOMETRY[kernel]
        paper_batch = experiments.PAPER_BATCH.get(kernel)
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
    return experiments.scaled_groups(default_groups, math.sqrt(scale))


def groups_total(groups):
    columns, rows = parse_pair(groups)
    return columns * rows


# ---- the FP32 peak ---------------------------------------------------------------

@dataclasses.dataclass
class Peak:
    """The device's FP32 peak and how it was found."""

    gflops: float | None
    formula: str


def gpu_peak(device_name, compute_units):
    """Returns the Peak of a GPU in GPU_PEAKS, or None when the table lacks it."""
    for pattern, part, lanes, ghz in GPU_PEAKS:
        if re.search(pattern, device_name):
            if part is None:
                return None
            gflops = compute_units * lanes * 2 * ghz
            return Peak(gflops, f"{part}, built-in table: {compute_units} SMs (rtcl's "
                                f"compute units) x {lanes} FP32 lanes x 2 flops (FMA) x "
                                f"{ghz:g} GHz boost = {gflops:,.0f} GFLOP/s")
    return None


def read_cpuinfo(path="/proc/cpuinfo"):
    """Returns the first processor's fields of /proc/cpuinfo as a dict ({} if absent)."""
    try:
        text = pathlib.Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError:
        return {}
    fields = {}
    for line in text.split("\n\n")[0].splitlines():
        name, _, value = line.partition(":")
        fields[name.strip()] = value.strip()
    return fields


def simd_lanes(flags):
    """Returns the FP32 lanes of the widest FMA vector the CPU flags name, or None."""
    flags = set(flags.split())
    if "avx512f" in flags:
        return 16, "avx512f"
    if "avx2" in flags and "fma" in flags:
        return 8, "avx2+fma"
    return None


def cpu_peak(stats, cpuinfo, fma_units):
    """Returns the Peak of a CPU device, or None when it cannot be computed."""
    lanes = simd_lanes(cpuinfo.get("flags", ""))
    clock_mhz = stats.get("max_clock_mhz") or 0
    units = stats.get("compute_units") or 0
    if not lanes or not fma_units or not clock_mhz or not units:
        return None
    lane_count, flag = lanes
    try:
        per_package = int(cpuinfo.get("cpu cores", "")) / int(cpuinfo.get("siblings", ""))
    except (ValueError, ZeroDivisionError):
        per_package = 1.0
    cores = units * min(per_package, 1.0)
    smt = "" if per_package >= 1 else \
        f" ({units} compute units = hardware threads; {cpuinfo['cpu cores']} cores per " \
        f"{cpuinfo['siblings']} threads)"
    gflops = cores * lane_count * fma_units * 2 * clock_mhz / 1e3
    return Peak(gflops, f"CPU: {cores:g} cores{smt} x {lane_count} FP32 lanes ({flag} in "
                        f"/proc/cpuinfo) x {fma_units} FMA unit(s) per core (--fma-units) x "
                        f"2 flops (FMA) x {clock_mhz} MHz (rtcl's max_clock_mhz, "
                        f"CL_DEVICE_MAX_CLOCK_FREQUENCY) = {gflops:,.1f} GFLOP/s")


def find_peak(stats, arguments, cpuinfo):
    """Returns the Peak for the device of stats; UsageError when it needs an option."""
    if arguments.peak_gflops:
        return Peak(arguments.peak_gflops,
                    f"given on the command line: --peak-gflops {arguments.peak_gflops:g}")
    device = stats["device"]
    units = stats.get("compute_units")
    if units:
        peak = gpu_peak(device, units)
        if peak:
            return peak
    is_cpu = "Portable Computing Language" in device or re.match(r"(pthread|cpu|basic)-",
                                                                 device)
    if is_cpu and cpuinfo:
        peak = cpu_peak(stats, cpuinfo, arguments.fma_units)
        if peak:
            return peak
        if simd_lanes(cpuinfo.get("flags", "")) and not arguments.fma_units:
            raise UsageError(f"the FP32 peak of {device} needs the FMA units per core, which "
                             "the CPU flags do not tell: give --fma-units N (1 for AMD Zen 4, "
                             "2 for most Intel Xeon Gold/Platinum) or --peak-gflops X")
    raise UsageError(f"the FP32 peak of {device} is not in bench.py's table: give "
                     "--peak-gflops X")


# ---- running --------------------------------------------------------------------

class BenchProgress(experiments.Progress):
    """experiments' progress lines; a refused run ends its line with the reason."""

    def __init__(self, total, suffix=""):
        super().__init__(total)
        self.suffix = suffix    # appended to every description, e.g. ' at 500x500'

    def start(self, description):
        super().start(description + self.suffix)

    def fail(self, note="failed"):
        pass  # the caller ends the line: 'skipped: REASON' or the error

    def end(self, note):
        print(f" {note}", file=sys.stderr, flush=True)


class SilentProgress(BenchProgress):
    """No progress lines (the probe: its failure is the one line printed)."""

    def start(self, description):
        pass

    def finish(self, kernel_ms):
        pass

    def end(self, note):
        pass


def run_one(settings, progress, kernel, workgroup=None, groups=None, batch=None,
            repeat=None):
    """Runs rtcl once in its own temporary folder; returns (stats, command, reason).

    A refusal by rtcl gives (None, command, rtcl's one-line reason); an rtcl that
    cannot be started or writes no usable statistics raises RtclFailed.
    """
    folder = pathlib.Path(tempfile.mkdtemp(dir=settings.temp_dir))
    own = dataclasses.replace(settings, temp_dir=folder)
    try:
        run = experiments.run_rtcl(own, progress, "run", kernel, workgroup, groups,
                                   repeat=repeat, batch=batch)
        return run.stats, hide_folders(run.command, settings.temp_dir), None
    except RtclFailed as error:
        if error.returncode is None:
            progress.end("failed")
            raise
        reason = error.reason
        if error.returncode < 0:
            reason = f"rtcl was killed by signal {-error.returncode} ({reason})"
        progress.end(f"skipped: {reason}")
        command = str(error).split("\n")[0].split(": ", 1)[-1]
        return None, hide_folders(command.replace(str(folder), "$TMP"), settings.temp_dir), \
            reason
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def hide_folders(command, temp_dir):
    """Returns command with the temporary folders shown as $TMP."""
    return command.replace(str(temp_dir), "$TMP")


def run_sweep(configs, settings, progress):
    """Runs every Config in order, filling in its stats or why it was skipped."""
    defaults = {}     # (kernel, work-group, batch) -> the default-count Config
    measured = {}     # Config.key() -> the Config measured with that geometry
    for config in configs:
        if config.group_scale not in (None, 1.0):
            default = defaults[(config.kernel, config.workgroup, config.batch)]
            if default.stats is None:
                config.skipped = f"the default-groups run was skipped ({default.skipped})"
                progress.start(config.description() + f" ({config.group_scale:g}x groups)")
                progress.end(f"skipped: {config.skipped}")
                continue
            config.groups = scaled_groups(default.stats["groups"], config.group_scale)
        if config.kernel in GROUP_KERNELS and config.groups is not None:
            twin = measured.get(config.key())
            if twin is not None:
                config.skipped = f"same geometry as {twin.description()}, measured there"
                twin.paper = twin.paper or config.paper
                progress.start(config.description())
                progress.end(f"skipped: {config.skipped}")
                continue
        repeat = 1 if config.kernel == "serial" else None
        config.stats, config.command, config.skipped = run_one(
            settings, progress, config.kernel, config.workgroup, config.groups,
            config.batch, repeat)
        if config.group_scale == 1.0:
            defaults[(config.kernel, config.workgroup, config.batch)] = config
        if config.stats is not None:
            measured[config.key()] = config
    if not any(config.stats for config in configs):
        raise RtclFailed("rtcl refused every configuration: "
                         + "; ".join(sorted({c.skipped for c in configs if c.skipped})))


def probe(settings, progress):
    """Runs rtcl on an 8x8 image to learn the device; returns its stats.

    RtclFailed (whatever rtcl's exit status) when it fails: without a device
    nothing else can run.
    """
    common = [option for option in settings.common]
    if "--size" in common:
        at = common.index("--size")
        del common[at:at + 2]
    tiny = dataclasses.replace(settings, common=common + ["--size", "8x8"])
    folder = pathlib.Path(tempfile.mkdtemp(dir=settings.temp_dir))
    try:
        own = dataclasses.replace(tiny, temp_dir=folder)
        return experiments.run_rtcl(own, progress, "probe", "naive", repeat=1,
                                    flops=False).stats
    finally:
        shutil.rmtree(folder, ignore_errors=True)


# ---- derived figures ------------------------------------------------------------

def figures(stats, peak_gflops):
    """Returns the derived figures of one run: GFLOP/s, % of peak, rays per pixel."""
    median = stats["kernel_ms"]
    gflop = stats.get("gflop")
    gflops = gflop * 1e3 / median if gflop is not None and median > 0 else None
    pixels = stats["width"] * stats["height"]
    rays = stats.get("rays")
    return {"gflops": gflops,
            "peak_percent": 100 * gflops / peak_gflops if gflops and peak_gflops else None,
            "rays_per_pixel": rays / pixels if rays is not None and pixels else None}


def csv_row(config, peak_gflops):
    """Returns the bench.csv row of a Config as a dict."""
    row = {"kernel": config.kernel, "workgroup": config.workgroup or "",
           "groups": config.groups or "", "group_scale": config.group_scale or "",
           "batch": config.batch or "", "paper": int(config.paper),
           "status": "skipped" if config.stats is None else "ok",
           "reason": config.skipped or "", "command": config.command}
    stats = config.stats
    if stats is None:
        return row
    per_item = stats.get("flops_per_item", {})
    row.update({"groups": stats["groups"], "groups_total": groups_total(stats["groups"]),
                "median_ms": stats["kernel_ms"], "min_ms": stats["kernel_ms_min"],
                "max_ms": stats["kernel_ms_max"], "repeat": stats["repeat"],
                "kernel_ms_all": " ".join(f"{ms:.6f}" for ms in stats["kernel_ms_all"]),
                "mrays_per_s": stats.get("mrays_per_s"),
                "parallel_efficiency": stats.get("parallel_efficiency"),
                "gflop": stats.get("gflop"), "total_flops": stats.get("total_flops"),
                "rays": stats.get("rays"), "flops_per_item_mean": per_item.get("mean"),
                "flops_per_item_max": per_item.get("max"),
                "flops_per_item_min": per_item.get("min"),
                "global_size": "x".join(map(str, stats["global_size"])),
                "width": stats["width"], "height": stats["height"],
                "max_depth": stats["max_depth"], "scene": stats["scene"],
                "scene_in_local_memory": int(stats.get("scene_in_local_memory", False)),
                "build_options": stats.get("build_options", "")})
    if config.workgroup is None:
        row["workgroup"] = stats["workgroup"]
    row.update(figures(stats, peak_gflops))
    return row


def to_csv(columns, rows):
    """Returns rows (dicts) as CSV text with the given columns."""
    stream = io.StringIO()
    writer = csv.DictWriter(stream, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({key: "" if value is None else value for key, value in row.items()})
    return stream.getvalue()


def number(value, digits=2):
    """Returns value with digits decimals and thousands separators, '–' if unknown."""
    return experiments.format_number(value, digits)


def sorted_for_table(configs):
    """Returns configs by kernel (serial first), measured by median time, then skipped."""
    def key(config):
        measured = config.stats is not None
        return (KERNEL_ORDER.index(config.kernel), not measured,
                config.stats["kernel_ms"] if measured else 0.0)
    return sorted(configs, key=key)


def best_per_kernel(configs):
    """Returns {kernel: the fastest measured Config}."""
    best = {}
    for config in configs:
        if config.stats is None:
            continue
        if config.kernel not in best or \
                config.stats["kernel_ms"] < best[config.kernel].stats["kernel_ms"]:
            best[config.kernel] = config
    return best


def note(config):
    """Returns the table's note: how the groups were chosen, paper, or why skipped."""
    parts = []
    if config.paper:
        parts.append("paper geometry" if config.kernel in experiments.PAPER
                     else "paper-like geometry")
    if config.group_scale == 1.0:
        parts.append("rtcl's default groups")
    elif config.group_scale:
        parts.append(f"{config.group_scale:g}x the default groups")
    if config.kernel == "wavefront":
        parts.append("groups of the primary-ray launch")
    if config.kernel == "serial":
        parts.append("one work-item, 1 timed launch")
    if config.skipped:
        parts.append(f"skipped: {config.skipped}")
    return "; ".join(parts)


def table_row(config, peak_gflops, best):
    """Returns the bench.md cells of a Config (bold when it is its kernel's best)."""
    stats = config.stats
    if stats is None:
        cells = [config.kernel, config.workgroup or "–", config.groups or "–",
                 str(config.batch or "–")] + ["–"] * 9 + [note(config)]
        return cells
    derived = figures(stats, peak_gflops)
    efficiency = stats.get("parallel_efficiency")
    cells = [config.kernel, stats["workgroup"] if config.kernel != "serial" else "–",
             stats["groups"] if config.kernel != "serial" else "–", str(config.batch or "–"),
             number(stats["kernel_ms"], 3), number(stats["kernel_ms_min"], 3),
             number(stats["kernel_ms_max"], 3), number(stats.get("mrays_per_s"), 1),
             number(derived["gflops"], 1), number(derived["peak_percent"], 2),
             experiments.format_percent(efficiency), number(stats.get("gflop"), 3),
             number(derived["rays_per_pixel"], 2), note(config)]
    if best:
        cells = [f"**{cell}**" if cell not in ("", "–") else cell for cell in cells]
    return cells


def render_bench_md(configs, peak, meta):
    """Returns bench.md."""
    stats = next(config.stats for config in configs if config.stats)
    best = best_per_kernel(configs)
    totals = {round(c.stats["gflop"], 6) for c in configs if c.stats and "gflop" in c.stats}
    work = (f"{totals.pop():.3f} GFLOP counted, the same for every configuration"
            if len(totals) == 1 else "counted work differs between configurations (it "
            "should not): " + ", ".join(f"{t:.3f}" for t in sorted(totals)) + " GFLOP")
    skipped = sum(1 for c in configs if c.stats is None)
    lines = [f"# rtcl benchmark: {stats['device']}", "",
             f"- device: {stats['device']}, {stats.get('compute_units', '?')} compute units, "
             f"max clock {stats.get('max_clock_mhz', '?')} MHz",
             f"- driver: {stats.get('driver', '?')}; OpenCL: {stats.get('device_version', '?')}",
             f"- scene: {stats['scene']}, {stats['width']}x{stats['height']}, max depth "
             f"{stats['max_depth']}; {work}",
             f"- commit: {meta['commit'] or 'unknown'}; rtcl {stats.get('rtcl_version', '?')};"
             f" {meta['date']}",
             f"- command: `{meta['command']}`",
             f"- times: median, min and max of {meta['repeat']} timed launches after one "
             "warm-up launch, from OpenCL profiling events (serial: one launch; wavefront: "
             "the sum of a frame's launches); flops and rays come from a separate, untimed "
             "counting run",
             f"- FP32 peak: {peak.formula}",
             "- GFLOP/s = counted GFLOP / median time; % of FP32 peak = GFLOP/s / peak; "
             "Mrays/s = rays (primary, secondary and shadow) / median time; rays/pixel = "
             "rays / pixels; parallel efficiency = mean / max flops per launched work-item "
             "(wavefront: over the work-items of all its launches)",
             f"- {len(configs)} configurations, {len(configs) - skipped} measured, "
             f"{skipped} skipped; the fastest of each kernel in bold", "",
             "## Best per kernel", "",
             experiments.markdown_table(
                 ("kernel", "geometry", "median ms", "GFLOP/s", "% of FP32 peak"),
                 [(kernel, describe(kernel, c.stats["workgroup"] if kernel != "serial"
                                    else None,
                                    c.stats["groups"] if kernel in GROUP_KERNELS else None,
                                    c.batch),
                   number(c.stats["kernel_ms"], 3),
                   number(figures(c.stats, peak.gflops)["gflops"], 1),
                   number(figures(c.stats, peak.gflops)["peak_percent"], 2))
                  for kernel, c in sorted(best.items(),
                                          key=lambda item: item[1].stats["kernel_ms"])]),
             "", "## Every configuration", "",
             experiments.markdown_table(TABLE_COLUMNS, [
                 table_row(c, peak.gflops, best.get(c.kernel) is c)
                 for c in sorted_for_table(configs)]), ""]
    return "\n".join(lines)


# ---- scaling ----------------------------------------------------------------------

@dataclasses.dataclass
class LinearFit:
    """y = intercept + slope * x by least squares, and how well it fits."""

    slope: float
    intercept: float
    r_squared: float
    max_relative_deviation: float   # max |y - fit| / y over the points
    points: int


def linear_fit(xs, ys):
    """Returns the LinearFit of ys over xs, or None with fewer than two distinct xs."""
    if len(xs) != len(ys) or len(set(xs)) < 2:
        return None
    n = len(xs)
    mean_x, mean_y = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mean_x) ** 2 for x in xs)
    slope = sum((x - mean_x) * (y - mean_y) for x, y in zip(xs, ys)) / sxx
    intercept = mean_y - slope * mean_x
    residuals = [y - (intercept + slope * x) for x, y in zip(xs, ys)]
    ss_res = sum(r * r for r in residuals)
    ss_tot = sum((y - mean_y) ** 2 for y in ys)
    if ss_tot > 0:
        r_squared = 1.0 - ss_res / ss_tot
    else:
        r_squared = 1.0 if ss_res == 0 else math.nan
    deviations = [abs(r) / abs(y) for r, y in zip(residuals, ys) if y]
    return LinearFit(slope, intercept, r_squared, max(deviations, default=math.nan), n)


@dataclasses.dataclass
class ScalingPoint:
    spheres: int
    size: str
    scene: str
    stats: dict | None = None
    skipped: str | None = None
    command: str = ""

    @property
    def megapixels(self):
        width, height = parse_pair(self.size)
        return width * height / 1e6


def parse_scaling_config(text):
    """Returns (kernel, work-group, groups, batch) from 'KERNEL:WxH[:GROUPS[:BATCH]]'."""
    parts = text.split(":")
    if not 1 <= len(parts) <= 4 or parts[0] not in KERNEL_ORDER:
        raise UsageError(f"--scaling-config {text!r}: expected KERNEL[:WxH[:GROUPS|default"
                         f"[:BATCH]]] with KERNEL one of {', '.join(KERNEL_ORDER)}")
    kernel = parts[0]
    workgroup = check_pair("--scaling-config", parts[1]) if len(parts) > 1 else "8x8"
    groups = parts[2] if len(parts) > 2 and parts[2] not in ("", "default") else None
    if groups:
        check_pair("--scaling-config", groups)
    batch = check_positive_int("--scaling-config", parts[3]) if len(parts) > 3 else None
    return kernel, workgroup, groups, batch


def scaling_choice(arguments, configs):
    """Returns (kernel, work-group, groups, batch, why) for the scaling runs."""
    if arguments.scaling_config:
        return (*parse_scaling_config(arguments.scaling_config), "given by --scaling-config")
    measured = [c for c in configs if c.stats and c.kernel != "serial"]
    if measured:
        fastest = min(measured, key=lambda c: c.stats["kernel_ms"])
        groups = None if fastest.group_scale == 1.0 or fastest.kernel not in GROUP_KERNELS \
            else fastest.stats["groups"]
        return (fastest.kernel, fastest.stats["workgroup"], groups, fastest.batch,
                "the fastest of the sweep")
    return (*SCALING_DEFAULT, "the default (no sweep in this call)")


def make_scenes(spheres, depth, folder):
    """Writes genscene.py's scene for each sphere count; returns {count: path}."""
    scenes = {}
    for count in spheres:
        path = folder / f"balls{count}.json"
        command = [sys.executable, str(TOOLS / "genscene.py"), "--balls", str(count),
                   "--seed", str(SCALING_SEED), "--size", "2000x2000", "--depth",
                   str(5 if depth is None else depth), "-o", str(path)]
        result = subprocess.run(command, capture_output=True, text=True)
        if result.returncode != 0:
            raise RtclFailed(f"genscene.py failed for {count} spheres: "
                             f"{experiments.rtcl_reason(result.stderr)}")
        scenes[count] = path
    return scenes


def run_scaling(arguments, settings, choice, temp_dir):
    """Runs the scaling points; returns them."""
    kernel, workgroup, groups, batch, _ = choice
    scenes = make_scenes(arguments.scaling_spheres, arguments.depth, temp_dir)
    device = [option for flag, value in (("-p", arguments.platform), ("-d", arguments.device),
                                         ("--depth", arguments.depth))
              if value is not None for option in (flag, str(value))]
    points = [ScalingPoint(count, size, f"genscene.py --balls {count} --seed {SCALING_SEED}")
              for count in arguments.scaling_spheres for size in arguments.scaling_sizes]
    progress = BenchProgress(len(points))
    for point in points:
        own = dataclasses.replace(settings, common=device + ["-s", str(scenes[point.spheres]),
                                                             "--size", point.size])
        progress.suffix = f" at {point.size}, {point.spheres} spheres"
        point.stats, point.command, point.skipped = run_one(
            own, progress, kernel, workgroup, groups, batch,
            1 if kernel == "serial" else None)
        point.command = point.command.replace(str(temp_dir), "$TMP")
    if not any(point.stats for point in points):
        raise RtclFailed("rtcl refused every scaling run: "
                         + "; ".join(sorted({p.skipped for p in points if p.skipped})))
    return points


def scaling_row(point):
    row = {"spheres": point.spheres, "width": parse_pair(point.size)[0],
           "height": parse_pair(point.size)[1], "megapixels": point.megapixels,
           "status": "ok" if point.stats else "skipped", "reason": point.skipped or "",
           "scene": point.scene, "command": point.command}
    stats = point.stats
    if stats:
        median = stats["kernel_ms"]
        row.update({"median_ms": median, "min_ms": stats["kernel_ms_min"],
                    "max_ms": stats["kernel_ms_max"],
                    "ms_per_megapixel": median / point.megapixels,
                    "ms_per_megapixel_sphere": median / point.megapixels / point.spheres,
                    "gflop": stats.get("gflop"), "mrays_per_s": stats.get("mrays_per_s"),
                    "parallel_efficiency": stats.get("parallel_efficiency"),
                    "repeat": stats["repeat"],
                    "kernel_ms_all": " ".join(f"{ms:.6f}" for ms in stats["kernel_ms_all"])})
        derived = figures(stats, None)
        row.update(gflops=derived["gflops"], rays_per_pixel=derived["rays_per_pixel"])
    return row


def scaling_fits(points):
    """Returns (by sphere count, by size, overall) fits of the measured points."""
    measured = [p for p in points if p.stats]
    by_spheres, by_size = {}, {}
    for count in sorted({p.spheres for p in measured}):
        subset = [p for p in measured if p.spheres == count]
        by_spheres[count] = linear_fit([p.megapixels for p in subset],
                                       [p.stats["kernel_ms"] for p in subset])
    for size in sorted({p.size for p in measured}, key=lambda s: groups_total(s)):
        subset = [p for p in measured if p.size == size]
        by_size[size] = linear_fit([p.spheres for p in subset],
                                   [p.stats["kernel_ms"] for p in subset])
    times = [p.stats["kernel_ms"] for p in measured]
    overall = linear_fit([p.megapixels * p.spheres for p in measured], times)
    work = [p.stats.get("gflop") for p in measured]
    by_work = linear_fit(work, times) if None not in work else None
    return by_spheres, by_size, overall, by_work


def fit_cells(fit, unit):
    if fit is None:
        return ["–", "–", "–", "–", "–"]
    return [str(fit.points), f"{fit.slope:.6g} {unit}", f"{fit.intercept:.4g} ms",
            f"{fit.r_squared:.5f}", f"{100 * fit.max_relative_deviation:.1f}%"]


def render_scaling_md(points, choice, meta):
    stats = next(p.stats for p in points if p.stats)
    kernel, workgroup, groups, batch, why = choice
    by_spheres, by_size, overall, by_work = scaling_fits(points)
    rows = []
    for point in points:
        row = scaling_row(point)
        if point.stats is None:
            rows.append([str(point.spheres), point.size, f"{point.megapixels:g}",
                         "–", "–", "–", "–", "–", "–", f"skipped: {point.skipped}"])
            continue
        rows.append([str(point.spheres), point.size, f"{point.megapixels:g}",
                     number(row["median_ms"], 3), number(row["ms_per_megapixel"], 3),
                     f"{row['ms_per_megapixel_sphere']:.5f}", number(row["gflop"], 3),
                     number(row["rays_per_pixel"], 2),
                     experiments.format_percent(row["parallel_efficiency"]), ""])
    fit_header = ("points", "slope", "intercept", "R²", "largest deviation from the fit")
    default_groups = "; rtcl's default groups at each size" \
        if kernel in GROUP_KERNELS and not groups else ""
    lines = [f"# rtcl scaling: {stats['device']}", "",
             f"- configuration: `{describe(kernel, workgroup, groups, batch)}` ({why}"
             f"{default_groups})",
             f"- scenes: tools/genscene.py --balls N --seed {SCALING_SEED} --size 2000x2000 "
             f"--depth {stats['max_depth']}, rendered at each size with --size",
             f"- driver: {stats.get('driver', '?')}; OpenCL: {stats.get('device_version', '?')}",
             f"- commit: {meta['commit'] or 'unknown'}; {meta['date']}",
             f"- command: `{meta['command']}`",
             f"- times: median of {meta['repeat']} timed launches after one warm-up launch "
             "(OpenCL profiling events)", "",
             experiments.markdown_table(
                 ("spheres", "size", "megapixels", "median ms", "ms / megapixel",
                  "ms / (megapixel × sphere)", "GFLOP", "rays/pixel",
                  "parallel efficiency", "note"), rows),
             "", "## Linearity (least squares)", "",
             "Linear in pixels, per sphere count: ms = intercept + slope × megapixels", "",
             experiments.markdown_table(("spheres",) + fit_header,
                                        [[str(count)] + fit_cells(fit, "ms/MP")
                                         for count, fit in by_spheres.items()]),
             "", "Linear in spheres, per size: ms = intercept + slope × spheres", "",
             experiments.markdown_table(("size",) + fit_header,
                                        [[size] + fit_cells(fit, "ms/sphere")
                                         for size, fit in by_size.items()]),
             "", "Every point: ms = intercept + slope × (megapixels × spheres)", "",
             experiments.markdown_table(fit_header, [fit_cells(overall, "ms/(MP·sphere)")]),
             "", "Every point against the counted work: ms = intercept + slope × GFLOP", "",
             experiments.markdown_table(fit_header, [fit_cells(by_work, "ms/GFLOP")]),
             "", "R² = 1 − (residual sum of squares) / (total sum of squares); the largest "
             "deviation is max |measured − fit| / measured over the points of the fit. "
             "Through two points a line fits exactly (R² = 1): the check needs three or "
             "more.", ""]
    return "\n".join(lines)


# ---- output ---------------------------------------------------------------------

def write_all_atomically(files):
    """Writes {path: text} all or nothing.

    Every file goes to a temporary file first; then each is renamed over its
    target, the previous version kept aside until all are in place, so that a
    failure part-way leaves every target as it was.
    """
    temporaries, kept, placed = [], {}, []
    try:
        for path, text in files.items():
            path.parent.mkdir(parents=True, exist_ok=True)
            descriptor, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
            temporaries.append(temporary)
            with os.fdopen(descriptor, "w", encoding="utf-8", newline="") as stream:
                stream.write(text)
            os.chmod(temporary, 0o666 & ~experiments.flops_hist.current_umask())
        for path, temporary in zip(files, temporaries):
            if path.exists():
                keep = f"{temporary}.previous"
                os.rename(path, keep)
                kept[path] = keep
            os.replace(temporary, path)
            placed.append(path)
    except BaseException:
        for path in placed:
            path.unlink(missing_ok=True)
        for path, keep in kept.items():
            os.rename(keep, path)
        raise
    finally:
        for temporary in temporaries:
            if os.path.exists(temporary):
                os.unlink(temporary)
    for keep in kept.values():
        os.unlink(keep)


# ---- options --------------------------------------------------------------------

class Parser(argparse.ArgumentParser):
    """argparse that reports a bad option in one line (no usage) with exit status 2."""

    def error(self, message):
        raise UsageError(message)


def check_pair(option, text):
    if not re.fullmatch(r"[1-9][0-9]{0,4}x[1-9][0-9]{0,4}", text):
        raise UsageError(f"{option}: expected WxH with positive integers, got {text!r}")
    return text


def check_positive_int(option, text):
    if not re.fullmatch(r"[1-9][0-9]{0,8}", text):
        raise UsageError(f"{option}: expected a positive integer, got {text!r}")
    return int(text)


def split_list(option, text, convert):
    items = [item.strip() for item in text.split(",")]
    if not text.strip() or any(not item for item in items):
        raise UsageError(f"{option}: expected a comma-separated list, got {text!r}")
    return tuple(convert(option, item) for item in items)


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
                                "counts and batches on one device (bench.csv, bench.md).")
    parser.add_argument("--rtcl", default="./rtcl", help="the rtcl program (default %(default)s)")
    parser.add_argument("-p", "--platform", type=int, help="OpenCL platform index")
    parser.add_argument("-d", "--device", type=int, help="device index within the platform")
    parser.add_argument("--scene", help="scene file (default: rtcl's built-in paper60)")
    parser.add_argument("--size", help="image size WxH (default: the scene's; "
                                       f"{QUICK['size']} with --quick)")
    parser.add_argument("--depth", type=int, help="maximum ray depth (default: the scene's)")
    parser.add_argument("--repeat", "-r", type=int,
                        help=f"timed launches per configuration (default {DEFAULT_REPEAT}; "
                             f"at least {MIN_REPEAT} unless --quick, whose default is "
                             f"{QUICK['repeat']})")
    parser.add_argument("--quick", action="store_true",
                        help=f"a smoke run: --size {QUICK['size']}, a smaller sweep, fewer "
                             "launches allowed, small scaling sizes")
    parser.add_argument("--out", default="docs/results",
                        help="results folder; a sub-folder per device (default %(default)s)")
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
                        help="the device's FP32 peak in GFLOP/s (needed where bench.py "
                             "cannot compute it)")
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
    if a.no_sweep and not a.scaling:
        raise UsageError("--no-sweep without --scaling leaves nothing to run")
    if a.no_sweep and (a.paper_only or a.serial):
        raise UsageError("--no-sweep contradicts --paper-only and --serial")
    return a


# ---- main -----------------------------------------------------------------------

def run_benchmark(arguments, temp_dir, command_line):
    """Runs everything; returns {path: text} of the files to write."""
    common = experiments.common_options(arguments)
    settings = experiments.Settings(arguments.rtcl, common, arguments.repeat, temp_dir)
    try:
        device_stats = probe(settings, SilentProgress(1))
    except RtclFailed as error:
        raise RtclFailed(f"rtcl failed on an 8x8 probe run: {error.reason}") from None
    peak = find_peak(device_stats, arguments, read_cpuinfo())
    print(f"FP32 peak: {peak.formula}", file=sys.stderr)
    meta = {"commit": experiments.git_describe(), "repeat": arguments.repeat,
            "command": command_line,
            "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")}
    out_dir = pathlib.Path(arguments.out) / experiments.device_slug(device_stats["device"])
    files = {}
    configs = []
    if not arguments.no_sweep:
        configs = plan(arguments.kernels, arguments.workgroups, arguments.group_scales,
                       arguments.batches, arguments.paper_only, arguments.serial)
        run_sweep(configs, settings, BenchProgress(len(configs)))
        files[out_dir / "bench.csv"] = to_csv(CSV_COLUMNS, [csv_row(c, peak.gflops)
                                                            for c in configs])
        files[out_dir / "bench.md"] = render_bench_md(configs, peak, meta)
    if arguments.scaling:
        choice = scaling_choice(arguments, configs)
        print(f"scaling: {describe(*choice[:4])} ({choice[4]})", file=sys.stderr)
        points = run_scaling(arguments, settings, choice, temp_dir)
        files[out_dir / "scaling.csv"] = to_csv(SCALING_COLUMNS,
                                                [scaling_row(p) for p in points])
        files[out_dir / "scaling.md"] = render_scaling_md(points, choice, meta)
    return files


def main(argv=None):
    program = pathlib.Path(sys.argv[0]).name
    argv = sys.argv[1:] if argv is None else argv
    command_line = shlex.join(["tools/bench.py", *argv])
    try:
        arguments = parse_arguments(argv)
        with tempfile.TemporaryDirectory(prefix="rtcl-bench-") as temp_name:
            files = run_benchmark(arguments, pathlib.Path(temp_name), command_line)
        write_all_atomically(files)
    except UsageError as error:
        print(f"{program}: error: {error}", file=sys.stderr)
        return 2
    except RtclFailed as error:
        print(f"{program}: error: {error}", file=sys.stderr)
        return 1
    except (OSError, ValueError, KeyError) as error:
        print(f"{program}: error: {experiments.flops_hist.one_line(error)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"\n{program}: interrupted; nothing written", file=sys.stderr)
        return 130
    for path in files:
        print(f"{program}: wrote {path}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
