#!/usr/bin/env python3
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
  - unless --no-sweep, every parallel kernel again at the fastest geometry of a
    small sweep: every work-group shape of SWEEP_WORKGROUPS at rtcl's default
    group count, then, for cyclic, dynamic and persistent, the fastest shape with
    the group count scaled up to 4x and with the paper-like group count (-r 3 per
    sweep run).
The paper measured neither persistent nor wavefront (its section 3.4 proposed
such schemes and judged them impossible on a GPU), so their paper cells are empty.
Every run is one `rtcl --flops --stats` call: rtcl counts flops in one launch and
times others without counting.  For the wavefront, rtcl counts every launch of the
frame (the primary-ray launch, then one per bounce) and writes their work-items
one after the other; its parallel efficiency and its histogram cover the
work-items of all its launches.  Under OUT/<device-slug>/ it writes
  table1.md          Table 1, ours beside the paper's, with the commands used;
  speedup.png        Figure 6: speedup per implementation, ours and the paper's;
  histograms.png     Figure 7: flops per work-item, paper(-like) geometries;
  histograms_best.png  the same for the sweep's best geometries (with the sweep);
  results.json       every run's command and rtcl statistics.
The per-work-item .npy files stay in a temporary folder, deleted at the end.

    tools/experiments.py -p 0 -d 0                 # the full 2000x2000 experiment
    tools/experiments.py --quick                   # 400x400, a smaller sweep
    make experiments DEVICE="-p 0 -d 0"            # the same through make
"""

import argparse
import dataclasses
import datetime
import json
import math
import os
import pathlib
import re
import shlex
import subprocess
import sys
import tempfile

TOOLS = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(TOOLS))
import flops_hist  # noqa: E402  (found through the line above)

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = TOOLS.parent
# The paper's Table 1 and speedups (Figure 6); times in seconds.
PAPER = {
    "serial": {"workgroup": "-", "threads": "-", "time_s": 90.56, "gflops": None,
               "efficiency": None, "speedup": 1.0},
    "naive": {"workgroup": "16x10", "threads": "2000x2000", "time_s": 1.75,
              "gflops": 10.91, "efficiency": 0.1120, "speedup": 52.0},
    "cyclic": {"workgroup": "8x8", "threads": "200x200", "time_s": 0.43,
               "gflops": 44.10, "efficiency": 0.7744, "speedup": 211.0},
    "dynamic": {"workgroup": "8x8", "threads": "80x80", "time_s": 0.44,
                "gflops": 43.37, "efficiency": 0.8536, "speedup": 206.0},
}
PARALLEL_KERNELS = ("naive", "cyclic", "dynamic", "persistent", "wavefront")
# The kernels that take --groups (persistent work-groups).
GROUP_KERNELS = ("cyclic", "dynamic", "persistent")
# The paper's geometries: kernel -> (work-group, groups or None); for persistent
# and wavefront, which the paper did not run, the nearest: dynamic's geometry,
# and the 8x8 work-group of the primary-ray launch.
PAPER_GEOMETRY = {"naive": ("16x10", None), "cyclic": ("8x8", "25x25"),
                  "dynamic": ("8x8", "10x10"), "persistent": ("8x8", "10x10"),
                  "wavefront": ("8x8", None)}
# --batch for the kernels that take it (pixels per fetch).
PAPER_BATCH = {"persistent": 1}
SWEEP_WORKGROUPS = ("8x8", "16x8", "16x16", "32x4", "32x8")
SWEEP_GROUP_SCALES = (1.5, 2.0)         # per dimension: 2.25x and 4x the groups
QUICK_WORKGROUPS = ("8x8", "16x8")
QUICK_GROUP_SCALES = (2.0,)
QUICK_SIZE = "400x400"
SWEEP_REPEAT = 3
# What the tables and plots read from every --stats file.
REQUIRED_STATS = ("device", "kernel", "kernel_ms", "workgroup", "groups", "global_size",
                  "width", "height", "max_depth", "scene")
DEFAULT_REPEAT = 5


class RtclFailed(Exception):
    """rtcl exited non-zero; the message holds the command and rtcl's stderr.

    reason is rtcl's own one-line message (its first 'rtcl: ' line, else the first
    line of stderr), returncode its exit status (None when it did not run).
    """

    def __init__(self, message, reason=None, returncode=None):
        super().__init__(message)
        self.reason = reason or message.splitlines()[0]
        self.returncode = returncode


def rtcl_reason(stderr):
    """Returns rtcl's one-line message from its stderr, without the 'rtcl: ' prefix."""
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    for line in lines:
        if line.startswith("rtcl: "):
            return line[len("rtcl: "):]
    return lines[0] if lines else "no message"


@dataclasses.dataclass
class Run:
    """One rtcl call: what it was for, how it was called, what it reported."""

    role: str               # "paper", "reference", "sweep" or "best"
    kernel: str
    workgroup: str | None
    groups: str | None
    command: str            # the shell line, the temporary folder shown as $TMP
    stats: dict
    flops_path: pathlib.Path | None = None
    batch: int | None = None  # --batch, for the persistent kernel

    def to_json(self):
        return {"role": self.role, "kernel": self.kernel, "workgroup": self.workgroup,
                "groups": self.groups, "batch": self.batch, "command": self.command,
                "stats": self.stats}


@dataclasses.dataclass
class Settings:
    """The options every rtcl call shares, and how to call it."""

    rtcl: str
    common: list[str]       # device, scene, size and depth options
    repeat: int
    temp_dir: pathlib.Path


class Progress:
    """Prints '[3/14] cyclic -w 8x8 --groups 25x25 ... 12.3 ms' lines on stderr."""

    def __init__(self, total):
        self.total = total
        self.done = 0

    def start(self, description):
        self.done += 1
        print(f"[{self.done}/{self.total}] {description} ...", end="", file=sys.stderr,
              flush=True)

    def finish(self, kernel_ms):
        print(f" {kernel_ms:.1f} ms", file=sys.stderr, flush=True)

    def fail(self, note="failed"):
        print(f" {note}", file=sys.stderr, flush=True)

    def skip(self):
        """A planned run turned out to be a duplicate: count it off."""
        self.total -= 1


# ---- running rtcl -------------------------------------------------------------

def run_rtcl(settings, progress, role, kernel, workgroup=None, groups=None,
             repeat=None, flops=True, batch=None):
    """Runs rtcl once with --stats (and --flops) and returns the Run."""
    name = "-".join(part for part in (role, kernel, workgroup, groups,
                                      batch and f"b{batch}") if part)
    stats_path = settings.temp_dir / f"{name}.json"
    flops_path = settings.temp_dir / f"{name}.npy" if flops else None
    command = [settings.rtcl, "-k", kernel, *settings.common,
               "-r", str(repeat or settings.repeat), "-q",
               "-o", str(settings.temp_dir / f"{name}.ppm"), "--stats", str(stats_path)]
    if workgroup:
        command += ["-w", workgroup]
    if groups:
        command += ["--groups", groups]
    if batch:
        command += ["--batch", str(batch)]
    if flops_path:
        command += ["--flops", str(flops_path)]
    progress.start(describe(kernel, workgroup, groups, batch)
                   + (f" ({role})" if role in ("sweep", "best") else ""))
    try:
        result = subprocess.run(command, capture_output=True, text=True)
    except OSError as error:
        progress.fail()
        raise RtclFailed(f"cannot run {settings.rtcl}: {error.strerror}") from None
    if result.returncode != 0:
        progress.fail()
        raise RtclFailed(f"rtcl failed (exit {result.returncode}): {shlex.join(command)}\n"
                         f"{result.stderr.rstrip()}", rtcl_reason(result.stderr),
                         result.returncode)
    stats = json.loads(stats_path.read_text(encoding="utf-8"))
    missing = [key for key in REQUIRED_STATS if key not in stats]
    if flops_path and "gflop" not in stats:
        missing.append("gflop")
    if missing:
        progress.fail()
        raise RtclFailed(f"{stats_path.name} lacks {', '.join(missing)}: "
                         f"{shlex.join(command)}")
    progress.finish(stats["kernel_ms"])
    return Run(role, kernel, workgroup, groups, display_command(command, settings.temp_dir),
               stats, flops_path, batch)


def describe(kernel, workgroup, groups, batch=None):
    """Returns e.g. 'cyclic -w 8x8 --groups 25x25' or 'persistent ... --batch 2'."""
    text = kernel
    if workgroup:
        text += f" -w {workgroup}"
    if groups:
        text += f" --groups {groups}"
    if batch:
        text += f" --batch {batch}"
    return text


def display_command(command, temp_dir):
    """Returns command as a shell line with the temporary folder shown as $TMP."""
    return shlex.join(command).replace(str(temp_dir), "$TMP")


def planned_run_count(no_serial, no_reference, no_sweep, workgroups, group_scales):
    """Returns how many rtcl calls the experiment makes at most."""
    count = len(PARALLEL_KERNELS) + (0 if no_serial else 1) + (0 if no_reference else 1)
    if not no_sweep:
        for kernel in PARALLEL_KERNELS:
            count += len(workgroups) + 1  # the shapes, then the best one's rerun
            if kernel in GROUP_KERNELS:
                count += len(group_scales) + 1  # scaled counts and the paper's
    return count


# ---- the sweep ------------------------------------------------------------------

def parse_pair(text):
    """Returns '25x25' as (25, 25)."""
    first, second = text.lower().split("x")
    return int(first), int(second)


def scaled_groups(groups, scale):
    """Returns '10x10' scaled by 1.5 per dimension as '15x15' (at least 1x1)."""
    columns, rows = parse_pair(groups)
    return f"{max(1, round(columns * scale))}x{max(1, round(rows * scale))}"


def select_best(runs):
    """Returns the fastest run (median kernel time); ties go to higher efficiency."""
    if not runs:
        raise ValueError("no runs to choose from")
    return min(runs, key=lambda run: (run.stats["kernel_ms"],
                                      -(run.stats.get("parallel_efficiency") or 0.0)))


def sweep_kernel(settings, progress, kernel, workgroups, group_scales):
    """Returns the sweep runs of one kernel, the best geometry's last."""
    batch = PAPER_BATCH.get(kernel)
    runs = [run_rtcl(settings, progress, "sweep", kernel, workgroup, repeat=SWEEP_REPEAT,
                     batch=batch)
            for workgroup in workgroups]
    if kernel in GROUP_KERNELS:
        fastest = select_best(runs)
        default_groups = fastest.stats["groups"]
        candidates = [scaled_groups(default_groups, scale) for scale in group_scales]
        candidates.append(PAPER_GEOMETRY[kernel][1])
        tried = {default_groups}
        for groups in candidates:
            if groups in tried:
                progress.skip()
                continue
            tried.add(groups)
            runs.append(run_rtcl(settings, progress, "sweep", kernel, fastest.workgroup,
                                 groups, repeat=SWEEP_REPEAT, batch=batch))
    return runs


def remove_flops_files(runs):
    """Deletes the .npy files (and sidecars) of runs that no figure needs."""
    for run in runs:
        if run.flops_path:
            for path in (run.flops_path, flops_hist.sidecar_path(run.flops_path)):
                path.unlink(missing_ok=True)
            run.flops_path = None


# ---- derived figures ------------------------------------------------------------

def speedup(baseline_ms, kernel_ms):
    """Returns baseline_ms / kernel_ms, or None when either is unknown or zero."""
    if not baseline_ms or not kernel_ms:
        return None
    return baseline_ms / kernel_ms


def baseline_ms(runs, kernel):
    """Returns the median time of the first run of kernel, None if there is none."""
    for run in runs:
        if run.kernel == kernel:
            return run.stats["kernel_ms"]
    return None


def device_slug(device_name):
    """Returns a folder name for a device, e.g. 'nvidia-h100-80gb-hbm3'.

    The platform in trailing parentheses is dropped.  PoCL names its CPU devices
    '<driver>-<llvm cpu>-<model>' (e.g. 'pthread-skylake-avx512-AMD EPYC'): those
    become 'pocl-<model>' (e.g. 'pocl-amd-epyc').
    """
    name = re.sub(r"\s*\([^()]*\)\s*$", "", device_name).strip() or device_name
    platform = device_name[len(name):]
    if "Portable Computing Language" in platform or re.match(r"(pthread|cpu|basic)-", name):
        parts = name.split("-")
        model_at = next((i for i, part in enumerate(parts) if re.search(r"[A-Z]", part)),
                        len(parts) - 1)
        name = "pocl " + "-".join(parts[model_at:])
    slug = re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-")
    return slug[:64].rstrip("-") or "unknown-device"


def git_commit():
    """Returns the short commit of the rtcl checkout ('-dirty' if modified), or None."""
    try:
        commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT,
                                capture_output=True, text=True, check=True).stdout.strip()
        changes = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"],
                                 cwd=ROOT, capture_output=True, text=True,
                                 check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return None
    return commit + ("-dirty" if changes else "")


def git_describe():
    """Returns `git describe --always --dirty` of the rtcl checkout, or None."""
    try:
        return subprocess.run(["git", "describe", "--always", "--dirty"], cwd=ROOT,
                              capture_output=True, text=True,
                              check=True).stdout.strip() or None
    except (OSError, subprocess.CalledProcessError):
        return None


# ---- Table 1 ------------------------------------------------------------------

TABLE_COLUMNS = ("Implementation", "work-group", "groups / threads", "time ms (median)",
                 "paper time", "GFLOP/s", "paper GFLOP/s", "parallel efficiency",
                 "paper efficiency", "speedup over serial", "paper speedup",
                 "speedup over CPU reference")


def format_number(value, digits=1, suffix=""):
    """Returns value with digits decimals (and suffix), or '–' when unknown."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "–"
    return f"{value:,.{digits}f}{suffix}"


def format_percent(fraction):
    return "–" if fraction is None else f"{100 * fraction:.2f}%"


def implementation_name(run):
    """Returns the table's first column for a run."""
    if run.kernel == "reference":
        return "CPU reference (1 core)"
    if run.role == "best":
        return f"{run.kernel} (best of sweep)"
    return run.kernel


def geometry_cells(run):
    """Returns the (work-group, groups / threads) cells of a run."""
    stats = run.stats
    if run.kernel in ("serial", "reference"):
        return "–", "1 work-item" if run.kernel == "serial" else "1 CPU thread"
    width, height = stats.get("global_size", [0, 0])
    threads = f"{stats.get('groups', '?')} / {width}x{height}"
    if run.kernel == "wavefront":
        threads += " (primary rays), then 1 launch per bounce"
    if run.batch:
        threads += f", batch {run.batch}"
    return stats.get("workgroup", "?"), threads


def table_row(run, serial_ms, reference_ms):
    """Returns the cells of one Table 1 row."""
    stats = run.stats
    kernel_ms = stats["kernel_ms"]
    paper = PAPER.get(run.kernel) if run.role in ("paper", "serial") else None
    paper = paper or {}
    workgroup, threads = geometry_cells(run)
    return (implementation_name(run), workgroup, threads, format_number(kernel_ms, 2),
            format_number(paper.get("time_s"), 2, " s"),
            format_number(stats.get("gflops"), 2), format_number(paper.get("gflops"), 2),
            format_percent(stats.get("parallel_efficiency")),
            format_percent(paper.get("efficiency")),
            format_number(speedup(serial_ms, kernel_ms), 1),
            format_number(paper.get("speedup"), 0),
            format_number(speedup(reference_ms, kernel_ms), 2))


def markdown_table(header, rows):
    """Returns a markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return "\n".join(lines)


def table_runs(runs):
    """Returns the runs that Table 1 shows, in its order."""
    order = {"serial": 0, "reference": 1, "naive": 2, "cyclic": 3, "dynamic": 4,
             "persistent": 5, "wavefront": 6}
    shown = [run for run in runs if run.role != "sweep"]
    return sorted(shown, key=lambda run: (run.role == "best", order.get(run.kernel, 9)))


def device_run(runs):
    """Returns a run on the OpenCL device (not the CPU reference)."""
    return next(run for run in runs if run.kernel != "reference")


def total_work_line(runs):
    """Returns a sentence saying whether every kernel counted the same total flops."""
    totals = {run.stats["gflop"] for run in runs if run.stats.get("gflop") is not None}
    if not totals:
        return "Total work: not counted."
    if len(totals) == 1:
        return f"Total work: {totals.pop():.3f} GFLOP, the same for every run."
    return ("Total work differs between runs (it should not, RENDERING.md): "
            + ", ".join(f"{total:.3f}" for total in sorted(totals)) + " GFLOP.")


def render_table1(runs, meta):
    """Returns table1.md: header, Table 1, the sweep and the commands used."""
    stats = device_run(runs).stats
    serial_ms, reference_ms = baseline_ms(runs, "serial"), baseline_ms(runs, "reference")
    lines = ["# Table 1 reproduced: rtcl on " + stats["device"], "",
             f"- device: {stats['device']} ({stats.get('device_version', '')})",
             f"- driver: {stats.get('driver', '')}",
             f"- scene: {stats['scene']}, {stats['width']}x{stats['height']}, "
             f"max depth {stats['max_depth']}",
             f"- rtcl {stats.get('rtcl_version', '?')}, commit {meta.get('commit') or 'unknown'}, "
             f"{meta['date']}",
             f"- times: median of {meta['repeat']} launches (sweep: {SWEEP_REPEAT}); the "
             "paper's are in seconds for 2000x2000 on the server Lincoln, ours in "
             "milliseconds",
             "- speedup over serial: our serial kernel is one work-item on the device; "
             "the paper's serial is a CPU program",
             f"- {total_work_line(runs)}", *beyond_the_paper_lines(runs), "",
             markdown_table(TABLE_COLUMNS, [table_row(run, serial_ms, reference_ms)
                                            for run in table_runs(runs)])]
    sweep = [run for run in runs if run.role == "sweep"]
    if sweep:
        lines += ["", "## Sweep", "",
                  markdown_table(("kernel", "work-group", "groups / threads", "time ms",
                                  "GFLOP/s", "parallel efficiency"),
                                 [sweep_row(run) for run in sweep])]
    lines += ["", "## Commands", "", "```"]
    lines += [run.command for run in runs]
    lines += ["```", ""]
    return "\n".join(lines)


def beyond_the_paper_lines(runs):
    """Returns the header lines that explain the persistent and wavefront rows."""
    kernels = {run.kernel for run in runs}
    lines = []
    if kernels & {"persistent", "wavefront"}:
        lines.append("- persistent and wavefront go beyond the paper (docs/wavefront.md): "
                     "it measured neither, so their paper cells are empty")
    if "persistent" in kernels:
        lines.append("- persistent: each work-item fetches `batch` pixels at a time from a "
                     "global counter; paper-like row: dynamic's 8x8 work-groups and "
                     "10x10 groups, batch 1")
    if "wavefront" in kernels:
        lines.append("- wavefront: time = sum of every launch of a frame (primary rays, "
                     "then one launch per bounce); the work-group and groups are those of "
                     "the primary-ray launch (bounce launches are 1D, as many work-items a "
                     "group); parallel efficiency = mean / max flops over the work-items "
                     "of all launches")
    return lines


def sweep_row(run):
    workgroup, threads = geometry_cells(run)
    return (run.kernel, workgroup, threads, format_number(run.stats["kernel_ms"], 2),
            format_number(run.stats.get("gflops"), 2),
            format_percent(run.stats.get("parallel_efficiency")))


# ---- Figure 6 -----------------------------------------------------------------

def speedup_bars(runs):
    """Returns [(label, ours over serial, ours over reference, paper)] per parallel run."""
    serial_ms, reference_ms = baseline_ms(runs, "serial"), baseline_ms(runs, "reference")
    bars = []
    for run in table_runs(runs):
        if run.kernel not in PARALLEL_KERNELS:
            continue
        paper = PAPER.get(run.kernel, {}).get("speedup") if run.role == "paper" else None
        label = run.kernel if run.role == "paper" else f"{run.kernel}\n(best)"
        kernel_ms = run.stats["kernel_ms"]
        bars.append((label, speedup(serial_ms, kernel_ms), speedup(reference_ms, kernel_ms),
                     paper))
    return bars


def plot_speedup(runs, out_path, device_name):
    """Writes Figure 6: grouped bars of speedup, ours and the paper's."""
    bars = speedup_bars(runs)
    series = (("ours, over the serial kernel", 1, "tab:blue"),
              ("ours, over the CPU reference", 2, "tab:green"),
              ("paper, over serial C on the CPU", 3, "tab:gray"))
    width = 0.8 / len(series)
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
        flops_hist.save_figure_atomically(figure, out_path)
    finally:
        plt.close(figure)


# ---- the experiment -------------------------------------------------------------

def common_options(arguments):
    """Returns the rtcl options shared by every run."""
    options = []
    for flag, value in (("-p", arguments.platform), ("-d", arguments.device),
                        ("-s", arguments.scene), ("--size", arguments.size),
                        ("--depth", arguments.depth)):
        if value is not None:
            options += [flag, str(value)]
    return options


def run_experiment(arguments, temp_dir):
    """Runs every configuration and returns the list of Runs."""
    workgroups = QUICK_WORKGROUPS if arguments.quick else SWEEP_WORKGROUPS
    group_scales = QUICK_GROUP_SCALES if arguments.quick else SWEEP_GROUP_SCALES
    settings = Settings(arguments.rtcl, common_options(arguments), arguments.repeat, temp_dir)
    progress = Progress(planned_run_count(arguments.no_serial, arguments.no_reference,
                                          arguments.no_sweep, workgroups, group_scales))
    runs = []
    if not arguments.no_serial:
        runs.append(run_rtcl(settings, progress, "serial", "serial", repeat=1))
        remove_flops_files(runs)
    if not arguments.no_reference:
        runs.append(run_rtcl(settings, progress, "reference", "reference", repeat=1,
                             flops=False))
    for kernel in PARALLEL_KERNELS:
        workgroup, groups = PAPER_GEOMETRY[kernel]
        runs.append(run_rtcl(settings, progress, "paper", kernel, workgroup, groups,
                             batch=PAPER_BATCH.get(kernel)))
    if not arguments.no_sweep:
        for kernel in PARALLEL_KERNELS:
            sweep = sweep_kernel(settings, progress, kernel, workgroups, group_scales)
            remove_flops_files(sweep)
            best = select_best(sweep)
            best_groups = best.stats["groups"] if kernel in GROUP_KERNELS else None
            runs += sweep
            runs.append(run_rtcl(settings, progress, "best", kernel, best.workgroup,
                                 best_groups, batch=best.batch))
    return runs


def write_outputs(runs, arguments):
    """Writes table1.md, speedup.png, histograms and results.json; returns the folder."""
    stats = device_run(runs).stats
    out_dir = pathlib.Path(arguments.out) / device_slug(stats["device"])
    out_dir.mkdir(parents=True, exist_ok=True)
    meta = {"commit": git_commit(), "repeat": arguments.repeat,
            "date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")}
    write_text_atomically(out_dir / "table1.md", render_table1(runs, meta))
    plot_speedup(runs, out_dir / "speedup.png", stats["device"])
    for role, name in (("paper", "histograms.png"), ("best", "histograms_best.png")):
        flops_files = [load_checked_flops(run.flops_path) for run in runs
                       if run.role == role and run.flops_path]
        if flops_files:
            title = f"Flops per work-item (Figure 7), {role} geometries: {stats['device']}"
            flops_hist.plot_flops_histograms(flops_files, out_dir / name, log=True,
                                             title=title)
    results = {"meta": meta, "paper": PAPER, "runs": [run.to_json() for run in runs]}
    write_text_atomically(out_dir / "results.json", json.dumps(results, indent=2) + "\n")
    return out_dir


def load_checked_flops(path):
    """Returns flops_hist's FlopsFile for path, warning where its sidecar disagrees."""
    flops_file = flops_hist.load_flops(path)
    for problem in flops_hist.sidecar_mismatches(flops_file):
        print(f"warning: {path.name}.json: {problem}", file=sys.stderr)
    return flops_file


def write_text_atomically(path, text):
    """Writes text to path through a temporary file in the same folder."""
    descriptor, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    try:
        with os.fdopen(descriptor, "w", encoding="utf-8") as stream:
            stream.write(text)
        os.chmod(temporary, 0o666 & ~flops_hist.current_umask())
        os.replace(temporary, path)
    except BaseException:
        os.unlink(temporary)
        raise


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description="Run the paper's experiment (Table 1, Figures 6 and 7) with rtcl.")
    parser.add_argument("--rtcl", default="./rtcl", help="the rtcl program (default %(default)s)")
    parser.add_argument("-p", "--platform", type=int, help="OpenCL platform index")
    parser.add_argument("-d", "--device", type=int, help="device index within the platform")
    parser.add_argument("--scene", help="scene file (default: rtcl's built-in paper60)")
    parser.add_argument("--size", help=f"image size WxH (default: the scene's; "
                                       f"{QUICK_SIZE} with --quick)")
    parser.add_argument("--depth", type=int, help="maximum ray depth (default: the scene's)")
    parser.add_argument("--repeat", type=int, default=DEFAULT_REPEAT,
                        help="timed launches per run (default %(default)s; the serial "
                             "kernel and the reference run once)")
    parser.add_argument("--quick", action="store_true",
                        help=f"--size {QUICK_SIZE} and a smaller sweep (smoke tests)")
    parser.add_argument("--out", default="docs/results",
                        help="results folder; a sub-folder per device (default %(default)s)")
    parser.add_argument("--no-sweep", action="store_true", help="only the paper's geometries")
    parser.add_argument("--no-reference", action="store_true",
                        help="skip the CPU reference run")
    parser.add_argument("--no-serial", action="store_true",
                        help="skip the serial kernel (slow on a GPU: one work-item); "
                             "the table then has no speedup over serial")
    arguments = parser.parse_args(argv)
    if arguments.quick and arguments.size is None:
        arguments.size = QUICK_SIZE
    if arguments.repeat < 1:
        parser.error("--repeat must be at least 1")
    return arguments


def main(argv=None):
    arguments = parse_arguments(argv)
    program = pathlib.Path(sys.argv[0]).name
    with tempfile.TemporaryDirectory(prefix="rtcl-experiments-") as temp_name:
        temp_dir = pathlib.Path(temp_name)
        try:
            runs = run_experiment(arguments, temp_dir)
            out_dir = write_outputs(runs, arguments)
        except RtclFailed as error:
            print(f"{program}: error: {error}", file=sys.stderr)
            return 1
        except (OSError, ValueError, flops_hist.FlopsFileError) as error:
            print(f"{program}: error: {flops_hist.one_line(error)}", file=sys.stderr)
            return 1
    print(f"{program}: results in {out_dir}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
