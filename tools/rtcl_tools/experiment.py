"""The paper's experiment run with rtcl: every paper geometry, a sweep, the outputs.

commands/experiments.py (rtcl-experiments, tools/experiments.py) is its command line,
and its docstring the description.
"""

import argparse
import dataclasses
import json
import os
import pathlib
import re
import sys

from . import files, peak, plots, table1
from . import flops as flops_module
from .histogram import histogram_from_json, histogram_of
from .paper import (GROUP_KERNELS, PAPER, PAPER_BATCH, PAPER_GEOMETRY, PARALLEL_KERNELS,
                    QUICK_GROUP_SCALES, QUICK_WORKGROUPS, SWEEP_GROUP_SCALES,
                    SWEEP_REPEAT, SWEEP_WORKGROUPS)
from .report import device_slug, git_commit, scene_stem, utc_now
from .requirements import install_command
from .runner import (REQUIRED_STATS, Progress, Run, Settings, common_options, describe,
                     run_rtcl, scaled_groups, schedule_path)
from .usage import command_name


def planned_run_count(no_serial, no_reference, no_sweep, workgroups, group_scales):
    """Returns how many rtcl calls the experiment makes at most."""
    count = len(PARALLEL_KERNELS) + (0 if no_serial else 1) + (0 if no_reference else 1)
    if not no_sweep:
        for kernel in PARALLEL_KERNELS:
            count += len(workgroups)
            if kernel in GROUP_KERNELS:
                count += len(group_scales) + 1  # scaled counts and the paper's
    return count


def select_best(runs):
    """Returns the fastest run (median kernel time); ties go to higher efficiency."""
    if not runs:
        raise ValueError("no runs to choose from")
    return min(runs, key=lambda run: (run.stats["kernel_ms"],
                                      -(run.stats.get("parallel_efficiency") or 0.0)))


def best_of_sweep(sweep):
    """Returns the sweep's fastest run again, as its kernel's "best" row.

    Not re-timed: a second timing of the same geometry can come out slower than
    another sweep entry (41.8 ms against the sweep's 37.8 ms, issue 12), and the
    row would then not be the fastest configuration shown.  The row shares the
    sweep entry's statistics, command and flops file.
    """
    return dataclasses.replace(select_best(sweep), role="best")


def sweep_kernel(settings, progress, kernel, workgroups, group_scales, journal=None):
    """Returns the sweep runs of one kernel, the best geometry's last."""
    batch = PAPER_BATCH.get(kernel)
    runs = [measure(settings, progress, "sweep", kernel, workgroup, repeat=SWEEP_REPEAT,
                    batch=batch, journal=journal)
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
            runs.append(measure(settings, progress, "sweep", kernel, fastest.workgroup,
                                groups, repeat=SWEEP_REPEAT, batch=batch, journal=journal))
    return runs


def measure(settings, progress, role, kernel, workgroup=None, groups=None, *, repeat=None,
            flops=True, batch=None, journal=None):
    """Runs rtcl once (runner.run_rtcl) and returns the Run with the histogram of its
    flops file (Figure 7's data), the file itself deleted: tens of MB each, they
    would fill the temporary folder over a sweep, and results.json keeps what the
    figures need.  A run the journal holds (--resume) is taken from it, not run
    again; a new one is added to it."""
    key = run_key(role, kernel, workgroup, groups, batch)
    if journal is not None and key in journal.runs:
        run = journal.runs[key]
        progress.start(describe(kernel, workgroup, groups, batch)
                       + (f" ({role})" if role in ("sweep", "best") else ""))
        progress.finish(run.stats["kernel_ms"], "measured before the interruption")
        return run
    run = run_rtcl(settings, progress, role, kernel, workgroup, groups, repeat, flops, batch)
    if run.flops_path:
        try:
            run.histogram = histogram_of(load_checked_flops(run.flops_path))
        finally:
            for path in (run.flops_path, flops_module.sidecar_path(run.flops_path),
                         schedule_path(run.flops_path)):
                path.unlink(missing_ok=True)
            run.flops_path = None
    if journal is not None:
        journal.add(key, run)
    return run


def run_key(role, kernel, workgroup, groups, batch):
    """Returns the name of one planned run, e.g. 'sweep-cyclic-8x8-50x50-b1'."""
    return "-".join(str(part) for part in (role, kernel, workgroup, groups,
                                           batch and f"b{batch}") if part)


def run_experiment(arguments, temp_dir, journal=None):
    """Runs every configuration and returns the list of Runs; with a journal, the
    runs it holds are taken from it and every new one is added to it."""
    workgroups = QUICK_WORKGROUPS if arguments.quick else SWEEP_WORKGROUPS
    group_scales = QUICK_GROUP_SCALES if arguments.quick else SWEEP_GROUP_SCALES
    # --accel none (the default): the paper's brute force, so that Table 1 stays
    # comparable with the paper's (issue 11 item 4); bvh: issue 11 item 8's study.
    settings = Settings(arguments.rtcl, common_options(arguments) + ["--accel", arguments.accel],
                        arguments.repeat, temp_dir)
    progress = Progress(planned_run_count(arguments.no_serial, arguments.no_reference,
                                          arguments.no_sweep, workgroups, group_scales))
    runs = []
    if not arguments.no_serial:
        runs.append(measure(settings, progress, "serial", "serial", repeat=1,
                            journal=journal))
    if not arguments.no_reference:
        runs.append(measure(settings, progress, "reference", "reference", repeat=1,
                            flops=False, journal=journal))
    for kernel in PARALLEL_KERNELS:
        workgroup, groups = PAPER_GEOMETRY[kernel]
        runs.append(measure(settings, progress, "paper", kernel, workgroup, groups,
                            batch=PAPER_BATCH.get(kernel), journal=journal))
    if not arguments.no_sweep:
        for kernel in PARALLEL_KERNELS:
            sweep = sweep_kernel(settings, progress, kernel, workgroups, group_scales,
                                 journal)
            runs += sweep
            runs.append(best_of_sweep(sweep))   # its histogram: histograms_best.png
    return runs


# --resume: the runs of a study so far, kept beside its results while it runs.
PROGRESS_NAME = "study-progress.json"
PROGRESS_FORMAT = "rtcl-experiments-progress"
# The options that make a study what it is: --resume takes them from the journal.
STUDY_OPTIONS = ("platform", "device", "scene", "accel", "size", "depth", "repeat", "quick",
                 "no_sweep", "no_reference", "no_serial", "no_plots", "peak_gflops",
                 "fma_units", "out", "update_committed")


class Journal:
    """The runs of one study so far, written to <folder>/study-progress.json after
    every run (atomically, as every file here), so that `--resume FOLDER` after an
    interruption or a failed run goes on where the study stopped: the runs it holds
    are not run again.  The folder is the study's results folder, made when the
    first run has named the device (folder_for(stats)); the journal is removed once
    the results are written."""

    def __init__(self, options, folder_for, folder=None, device=None, runs=None):
        self.options = options
        self.folder_for = folder_for
        self.folder = None if folder is None else pathlib.Path(folder)
        self.device = device
        self.runs = dict(runs or {})

    @property
    def path(self):
        return None if self.folder is None else self.folder / PROGRESS_NAME

    def add(self, key, run):
        """Keeps run (under its key) and rewrites the journal.  The CPU reference
        names no device: the journal is written from the first run on the device."""
        if run.kernel != "reference":
            device = run.stats["device"]
            if self.device is not None and device != self.device:
                raise ValueError(f"{self.path}: the study ran on {self.device}, this run "
                                 f"on {device}: not resumed (start a new study)")
            if self.folder is None:
                self.folder = pathlib.Path(self.folder_for(run.stats))
            self.device = device
        self.runs[key] = run
        if self.folder is None:
            return
        document = {"format": PROGRESS_FORMAT, "version": 1, "device": self.device,
                    "options": self.options,
                    "runs": [dict(item.to_json(), key=name) for name, item in self.runs.items()]}
        files.write_text(self.path, compact_number_lists(json.dumps(document, indent=1)) + "\n")

    def discard(self):
        """Removes the journal: the study's results are written."""
        if self.path is not None:
            files.remove(self.path)


def study_options(arguments):
    """Returns the options of arguments that define the study (STUDY_OPTIONS), the
    scene as an absolute path (a resumed study may run from another folder)."""
    options = {name: getattr(arguments, name) for name in STUDY_OPTIONS}
    if options["scene"] is not None:
        options["scene"] = os.path.abspath(options["scene"])
    if options["out"] is not None:
        options["out"] = os.path.abspath(options["out"])
    options["rtcl"] = os.path.abspath(arguments.rtcl) if arguments.rtcl else None
    return options


def load_journal(folder):
    """Returns the Journal in folder (--resume FOLDER); ValueError naming what is
    wrong when there is none or it is not one."""
    path = pathlib.Path(folder) / PROGRESS_NAME
    if not path.exists():
        raise ValueError(f"{folder}: no interrupted study here ({PROGRESS_NAME} is missing: "
                         "it is removed once a study's results are written)")
    data = read_results(path)
    if not isinstance(data, dict) or data.get("format") != PROGRESS_FORMAT \
            or not isinstance(data.get("options"), dict) \
            or not isinstance(data.get("runs"), list) or not isinstance(data.get("device"), str):
        raise ValueError(f"{path}: not the progress of a study (tools/experiments.py writes it)")
    options = data["options"]
    missing = [name for name in STUDY_OPTIONS if name not in options]
    if missing:
        raise ValueError(f"{path}: options lack {', '.join(missing)}")
    runs = {}
    for index, item in enumerate(data["runs"]):
        run = stored_run(path, index, item)
        runs[item.get("key") or run_key(run.role, run.kernel, run.workgroup, run.groups,
                                         run.batch)] = run
    return Journal(options, None, folder, data["device"], runs)


def study_folder(device_name, accel="none", scene=None):
    """Returns the name of one study's results folder.

    <device-slug> for the paper's study (--accel none on the built-in scene), the
    folder name of every result made before --accel; <device-slug>-<accel>-<scene
    stem> otherwise, e.g. nvidia-h200-bvh-paper60 or ...-bvh-lake-10.
    """
    folder = device_slug(device_name)
    if accel != "none" or scene is not None:
        folder += f"-{accel}-{scene_stem(scene)}"
    return folder


def results_folder(out, device_name, accel="none", scene=None):
    """Returns out/<study folder> (study_folder), e.g. docs/results/pocl-amd-epyc."""
    return pathlib.Path(out) / study_folder(device_name, accel, scene)


def study_peak(stats, peak_gflops=None, fma_units=None, cpuinfo=None):
    """Returns {"gflops", "formula"}: the FP32 peak of the device of stats (peak.py),
    gflops None when unknown; for a CPU also "cpuinfo", the fields of /proc/cpuinfo it
    is computed from.  cpuinfo: /proc/cpuinfo's fields when the device is this
    machine's CPU, {} otherwise (a stored study replotted elsewhere)."""
    options = argparse.Namespace(peak_gflops=peak_gflops, fma_units=fma_units)
    found = peak.find_peak(stats, options, cpuinfo or {})
    result = {"gflops": found.gflops, "formula": found.formula}
    if cpuinfo and peak.is_cpu_device(stats["device"]):
        result["cpuinfo"] = peak.peak_cpuinfo(cpuinfo)
    return result


def replot_cpuinfo(meta, stats, out_dir):
    """Returns the CPU fields --replot --fma-units computes the peak from: those
    results.json keeps, else this machine's when it is the study's CPU; ValueError
    when the study ran on no CPU or its CPU's fields are not at hand."""
    device = stats["device"]
    if not peak.is_cpu_device(device):
        raise ValueError(f"--fma-units: the study in {out_dir} ran on {device}, not a CPU: "
                         "its peak takes no FMA units (--peak-gflops X gives another)")
    stored = meta.get("peak", {}).get("cpuinfo") if isinstance(meta.get("peak"), dict) \
        else None
    if isinstance(stored, dict) and stored.get("flags") is not None:
        return stored
    here = peak.read_cpuinfo()
    model = here.get("model name", "")
    if model and model in device:
        return here
    raise ValueError(f"--fma-units: {out_dir}/results.json does not keep the flags of its "
                     f"CPU ({device}), and this machine's is another ({model or 'unknown'}): "
                     "give its peak with --peak-gflops X")


def study_meta(arguments, stats):
    """Returns results.json's meta: when and how the study was measured, and the
    device's FP32 peak (for the bounds table)."""
    return {"commit": git_commit(), "repeat": arguments.repeat, "date": utc_now(),
            "peak": study_peak(stats, arguments.peak_gflops, arguments.fma_units,
                               peak.read_cpuinfo()),
            "accel": arguments.accel, "scene": stats["scene"],
            "scene_stem": scene_stem(arguments.scene),
            "size": f"{stats['width']}x{stats['height']}", "depth": stats["max_depth"]}


FIGURES = ("speedup.png", "histograms.png", "histograms_best.png")


def write_outputs(runs, arguments, folder_for):
    """Writes results.json, table1.md and (unless --no-plots or without matplotlib) the
    figures into folder_for(the device's stats), a folder; returns (the folder, notes
    to print).  A figure this run does not draw is removed from the folder, lest it
    stand beside results it does not show.  Nothing is written when a file it would
    replace or remove is tracked by git (files.TrackedFileError)."""
    stats = table1.device_run(runs).stats
    out_dir = folder_for(stats)
    files.check_not_tracked([out_dir / name for name in ("results.json", "table1.md",
                                                         *FIGURES)])
    meta = study_meta(arguments, stats)
    results = {"meta": meta, "paper": PAPER, "runs": [run.to_json() for run in runs]}
    files.write_text(out_dir / "results.json", compact_number_lists(
        json.dumps(results, indent=2)) + "\n")
    files.write_text(out_dir / "table1.md", table1.render_table1(runs, meta))
    drawn, notes = draw_figures(out_dir, runs, meta, arguments.no_plots)
    for name in FIGURES:
        if name not in drawn:
            files.remove(out_dir / name)
    return out_dir, notes


def compact_number_lists(text):
    """Returns json.dumps(..., indent=2) text with every list of numbers on one line:
    the histograms' bins stay a line each, not a line a number."""
    number = r"-?[0-9][0-9.eE+-]*"
    # Only a newline after '[' and ',' (never inside a JSON string, where it is \n).
    pattern = re.compile(rf"\[\n\s*({number}(?:,\n\s*{number})*)\n\s*\]")
    return pattern.sub(lambda match: "[" + ", ".join(match.group(1).replace(",", " ").split())
                       + "]", text)


def figure_context(runs, meta):
    """Returns what the figures' titles name: the device, and the acceleration and
    scene where they are not the paper's (brute force on the built-in scene)."""
    return table1.device_run(runs).stats["device"] + table1.study_suffix(runs, meta)


def skipped_figures_note(out_dir, why, install=None):
    """Returns the one line saying the figures were not drawn and how to draw them
    (install: how to install matplotlib, when it is missing)."""
    return (f"figures skipped ({why}); `{command_name()} --replot {out_dir}` on a "
            "machine with matplotlib draws them from results.json"
            + (f" ({install} installs it here)" if install else ""))


def draw_figures(out_dir, runs, meta, no_plots=False):
    """Draws speedup.png and the histograms that runs hold data for.

    Returns (names drawn, notes): with no_plots, or without matplotlib, nothing is
    drawn and the note says how to draw the figures later.
    """
    missing = "--no-plots" if no_plots else plots.matplotlib_missing()
    if missing:
        if no_plots:
            return [], [skipped_figures_note(out_dir, missing)]
        return [], [skipped_figures_note(out_dir, f"matplotlib cannot be imported: {missing}",
                                         install_command(["matplotlib"]))]
    context = figure_context(runs, meta)
    plots.plot_speedup(table1.speedup_bars(runs), out_dir / "speedup.png", context)
    drawn = ["speedup.png"]
    for role, name in (("paper", "histograms.png"), ("best", "histograms_best.png")):
        histograms = [figure_histogram(run) for run in runs
                      if run.role == role and run.histogram]
        if histograms:
            title = f"Flops per work-item (Figure 7), {role} geometries: {context}"
            plots.plot_flops_histograms(histograms, out_dir / name, log=True, title=title)
            drawn.append(name)
    return drawn, []


def figure_histogram(run):
    """Returns run's histogram, its title also giving the run's SIMD efficiency
    (table1.simd_cells: measured, intersection / traversal, and modelled) and how
    many work-items traced pixels (from the schedule map): on a CPU the reason for
    dynamic's and persistent's near-zero parallel efficiency."""
    measured, modelled = table1.simd_cells(run.stats)
    lines = []
    if (measured, modelled) != ("–", "–"):
        lines.append(f"SIMD efficiency measured {measured}, modelled {modelled}")
    used = table1.used_items_cell(run.stats)
    if used != "–":
        lines.append(f"{used} work-items traced pixels")
    if not lines:
        return run.histogram
    return dataclasses.replace(run.histogram,
                               label="\n".join([run.histogram.label, *lines]))


def load_checked_flops(path):
    """Returns flops.FlopsFile for path, warning where its sidecar disagrees."""
    flops_file = flops_module.load_flops(path)
    for problem in flops_module.sidecar_mismatches(flops_file):
        print(f"warning: {path.name}.json: {problem}", file=sys.stderr)
    return flops_file


# --replot: the report redrawn from a stored results.json, without running rtcl.
RUN_ROLES = ("serial", "reference", "paper", "sweep", "best")
# Older results.json files hold no histograms: these figures are then kept.
KEPT_FIGURES = ("histograms.png", "histograms_best.png")


def read_results(path):
    """Returns the object stored in results.json at path; ValueError if unreadable."""
    try:
        with files.open_input(path, "r") as stream:
            text = stream.read()
    except (OSError, UnicodeDecodeError) as error:
        reason = getattr(error, "strerror", None) or "not UTF-8 text"
        raise ValueError(f"{path}: cannot read: {reason}") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: not valid JSON: {error}") from None


def stored_run(path, index, item):
    """Returns the Run of the results.json entry runs[index]; ValueError if malformed."""
    where = f"{path}: runs[{index}]"
    if not isinstance(item, dict) or item.get("role") not in RUN_ROLES:
        raise ValueError(f"{where}: expected an object with a role among {RUN_ROLES}")
    stats = item.get("stats")
    if not isinstance(item.get("kernel"), str) or not isinstance(item.get("command"), str) \
            or not isinstance(stats, dict):
        raise ValueError(f"{where}: expected a kernel, a command and stats")
    missing = [key for key in REQUIRED_STATS if key not in stats]
    if missing:
        raise ValueError(f"{where}: stats lack {', '.join(missing)}")
    kernel_ms = stats["kernel_ms"]
    if isinstance(kernel_ms, bool) or not isinstance(kernel_ms, (int, float)) \
            or not kernel_ms > 0:
        raise ValueError(f"{where}: kernel_ms is not a positive number")
    histogram = item.get("flops_histogram")   # absent before results.json kept them
    if histogram is not None:
        histogram = histogram_from_json(histogram, f"{where}: flops_histogram")
    return Run(item["role"], item["kernel"], item.get("workgroup"), item.get("groups"),
               item["command"], stats, batch=item.get("batch"), histogram=histogram)


def load_results(path):
    """Returns (meta, runs) of a results.json written by write_outputs; ValueError if not."""
    data = read_results(path)
    if not isinstance(data, dict) or not isinstance(data.get("meta"), dict) \
            or not isinstance(data.get("runs"), list):
        raise ValueError(f"{path}: expected an object with \"meta\" and \"runs\"")
    meta = data["meta"]
    if not isinstance(meta.get("date"), str) or not isinstance(meta.get("repeat"), int):
        raise ValueError(f"{path}: meta: expected the date and repeat of the measurement")
    runs = [stored_run(path, index, item) for index, item in enumerate(data["runs"])]
    if not any(run.kernel != "reference" for run in runs):
        raise ValueError(f"{path}: no run on an OpenCL device")
    return meta, runs


def best_rows_from_sweep(runs):
    """Returns runs with every stored "best" row replaced by best_of_sweep of its sweep.

    The old report re-timed the best geometry (issue 12); its row is dropped, and
    the fastest sweep entry, with its own time, follows the kernel's last sweep run.
    """
    sweep_runs = [run for run in runs if run.role == "sweep"]
    last = {run.kernel: run for run in sweep_runs}
    rebuilt = []
    for run in runs:
        if run.role == "best":
            continue
        rebuilt.append(run)
        if last.get(run.kernel) is run:
            rebuilt.append(best_of_sweep([entry for entry in sweep_runs
                                          if entry.kernel == run.kernel]))
    return rebuilt


def changed_best_geometries(old_runs, new_runs):
    """Returns 'kernel WGxGROUPS (now ...)' for each best row whose geometry changed."""
    def geometries(runs):
        return {run.kernel: f"{run.stats['workgroup']} {run.stats['groups']}"
                for run in runs if run.role == "best"}
    old, new = geometries(old_runs), geometries(new_runs)
    return [f"{kernel} {old[kernel]} (now {new[kernel]})"
            for kernel in old if kernel in new and old[kernel] != new[kernel]]


def replot(out_dir, no_plots=False, peak_gflops=None, fma_units=None):
    """Rewrites out_dir's table1.md and figures from its results.json.

    Runs no rtcl.  Histograms are redrawn from the histograms that results.json
    stores; one written before it stored them leaves histograms*.png as they are.
    Without matplotlib (or with no_plots) only table1.md is rewritten.  The bounds
    use peak_gflops when given, else the peak results.json stores, else the built-in
    table of GPU peaks; fma_units (a CPU study's) computes the peak again from the
    CPU's fields that results.json keeps (ValueError for a GPU's study, or one whose
    CPU's fields are not at hand).  Returns the lines to print: what was rewritten,
    kept or skipped.  Nothing is written when results.json is missing or malformed
    (ValueError).
    """
    out_dir = pathlib.Path(out_dir)
    files.check_not_tracked([out_dir / name for name in ("table1.md", *FIGURES)])
    meta, stored = load_results(out_dir / "results.json")
    runs = best_rows_from_sweep(stored)
    meta = dict(meta, regenerated={"date": utc_now(), "commit": git_commit()})
    stats = table1.device_run(runs).stats
    if fma_units is not None and peak_gflops is None:
        meta["peak"] = study_peak(stats, None, fma_units,
                                  replot_cpuinfo(meta, stats, out_dir))
    elif peak_gflops is not None or not isinstance(meta.get("peak"), dict):
        meta["peak"] = study_peak(stats, peak_gflops)
    text = table1.render_table1(runs, meta)
    drawn, notes = draw_figures(out_dir, runs, meta, no_plots)
    files.write_text(out_dir / "table1.md", text)
    notes.insert(0, "rewrote " + ", ".join(str(out_dir / name)
                                           for name in ["table1.md", *drawn]))
    if not drawn:
        return notes
    kept = [name for name in KEPT_FIGURES if name not in drawn and (out_dir / name).exists()]
    if kept:
        notes.append(f"kept {', '.join(kept)} as they are (results.json holds no "
                     "per-work-item flops)")
    changed = changed_best_geometries(stored, runs)
    if changed and "histograms_best.png" in kept:
        notes.append("histograms_best.png shows the old best geometries: "
                     + ", ".join(changed))
    return notes
