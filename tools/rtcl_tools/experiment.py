"""The paper's experiment run with rtcl: every paper geometry, a sweep, the outputs.

commands/experiments.py (rtcl-experiments, tools/experiments.py) is its command line,
and its docstring the description.
"""

import argparse
import dataclasses
import json
import pathlib
import re
import sys

from . import files, flops, peak, plots, table1
from .histogram import histogram_from_json, histogram_of
from .paper import (GROUP_KERNELS, PAPER, PAPER_BATCH, PAPER_GEOMETRY, PARALLEL_KERNELS,
                    QUICK_GROUP_SCALES, QUICK_WORKGROUPS, SWEEP_GROUP_SCALES,
                    SWEEP_REPEAT, SWEEP_WORKGROUPS)
from .report import device_slug, git_commit, scene_stem, utc_now
from .runner import (REQUIRED_STATS, Progress, Run, Settings, common_options, run_rtcl,
                     scaled_groups, schedule_path)
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


def sweep_kernel(settings, progress, kernel, workgroups, group_scales):
    """Returns the sweep runs of one kernel, the best geometry's last."""
    batch = PAPER_BATCH.get(kernel)
    runs = [measure(settings, progress, "sweep", kernel, workgroup, repeat=SWEEP_REPEAT,
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
            runs.append(measure(settings, progress, "sweep", kernel, fastest.workgroup,
                                groups, repeat=SWEEP_REPEAT, batch=batch))
    return runs


def measure(settings, progress, role, kernel, *args, **options):
    """Runs rtcl once (runner.run_rtcl) and returns the Run with the histogram of its
    flops file (Figure 7's data), the file itself deleted: tens of MB each, they
    would fill the temporary folder over a sweep, and results.json keeps what the
    figures need."""
    run = run_rtcl(settings, progress, role, kernel, *args, **options)
    if run.flops_path:
        try:
            run.histogram = histogram_of(load_checked_flops(run.flops_path))
        finally:
            for path in (run.flops_path, flops.sidecar_path(run.flops_path),
                         schedule_path(run.flops_path)):
                path.unlink(missing_ok=True)
            run.flops_path = None
    return run


def run_experiment(arguments, temp_dir):
    """Runs every configuration and returns the list of Runs."""
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
        runs.append(measure(settings, progress, "serial", "serial", repeat=1))
    if not arguments.no_reference:
        runs.append(measure(settings, progress, "reference", "reference", repeat=1,
                            flops=False))
    for kernel in PARALLEL_KERNELS:
        workgroup, groups = PAPER_GEOMETRY[kernel]
        runs.append(measure(settings, progress, "paper", kernel, workgroup, groups,
                            batch=PAPER_BATCH.get(kernel)))
    if not arguments.no_sweep:
        for kernel in PARALLEL_KERNELS:
            sweep = sweep_kernel(settings, progress, kernel, workgroups, group_scales)
            runs += sweep
            runs.append(best_of_sweep(sweep))   # its histogram: histograms_best.png
    return runs


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
    gflops None when unknown. cpuinfo: /proc/cpuinfo's fields when the device is
    this machine's CPU, {} otherwise (a stored study replotted elsewhere)."""
    options = argparse.Namespace(peak_gflops=peak_gflops, fma_units=fma_units)
    found = peak.find_peak(stats, options, cpuinfo or {})
    return {"gflops": found.gflops, "formula": found.formula}


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


def skipped_figures_note(out_dir, why):
    """Returns the one line saying the figures were not drawn and how to draw them."""
    return (f"figures skipped ({why}); `{command_name()} --replot {out_dir}` on a "
            "machine with matplotlib draws them from results.json")


def draw_figures(out_dir, runs, meta, no_plots=False):
    """Draws speedup.png and the histograms that runs hold data for.

    Returns (names drawn, notes): with no_plots, or without matplotlib, nothing is
    drawn and the note says how to draw the figures later.
    """
    missing = "--no-plots" if no_plots else plots.matplotlib_missing()
    if missing:
        why = missing if no_plots else f"matplotlib cannot be imported: {missing}"
        return [], [skipped_figures_note(out_dir, why)]
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
    flops_file = flops.load_flops(path)
    for problem in flops.sidecar_mismatches(flops_file):
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


def replot(out_dir, no_plots=False, peak_gflops=None):
    """Rewrites out_dir's table1.md and figures from its results.json.

    Runs no rtcl.  Histograms are redrawn from the histograms that results.json
    stores; one written before it stored them leaves histograms*.png as they are.
    Without matplotlib (or with no_plots) only table1.md is rewritten.  The bounds
    use peak_gflops when given, else the peak results.json stores, else the built-in
    table of GPU peaks.  Returns the
    lines to print: what was rewritten, kept or skipped.  Nothing is written when
    results.json is missing or malformed (ValueError).
    """
    out_dir = pathlib.Path(out_dir)
    files.check_not_tracked([out_dir / name for name in ("table1.md", *FIGURES)])
    meta, stored = load_results(out_dir / "results.json")
    runs = best_rows_from_sweep(stored)
    meta = dict(meta, regenerated={"date": utc_now(), "commit": git_commit()})
    if peak_gflops is not None or not isinstance(meta.get("peak"), dict):
        meta["peak"] = study_peak(table1.device_run(runs).stats, peak_gflops)
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
