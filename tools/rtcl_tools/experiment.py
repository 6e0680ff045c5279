"""The paper's experiment run with rtcl: every paper geometry, a sweep, the outputs.

tools/experiments.py is its command line (and its docstring the description).
"""

import dataclasses
import json
import pathlib
import sys

from . import files, flops, plots, table1
from .paper import (GROUP_KERNELS, PAPER, PAPER_BATCH, PAPER_GEOMETRY, PARALLEL_KERNELS,
                    QUICK_GROUP_SCALES, QUICK_WORKGROUPS, SWEEP_GROUP_SCALES,
                    SWEEP_REPEAT, SWEEP_WORKGROUPS)
from .report import device_slug, git_commit, utc_now
from .runner import (REQUIRED_STATS, Progress, Run, Settings, common_options, run_rtcl,
                     scaled_groups)


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


def remove_flops_files(runs, keep=None):
    """Deletes the .npy files (and sidecars) of runs that no figure needs."""
    for run in runs:
        if run.flops_path and run.flops_path != keep:
            for path in (run.flops_path, flops.sidecar_path(run.flops_path)):
                path.unlink(missing_ok=True)
            run.flops_path = None


def run_experiment(arguments, temp_dir):
    """Runs every configuration and returns the list of Runs."""
    workgroups = QUICK_WORKGROUPS if arguments.quick else SWEEP_WORKGROUPS
    group_scales = QUICK_GROUP_SCALES if arguments.quick else SWEEP_GROUP_SCALES
    # --accel none: the paper's brute force, so that Table 1 stays comparable
    # with the paper's (issue 11 item 4).
    settings = Settings(arguments.rtcl, common_options(arguments) + ["--accel", "none"],
                        arguments.repeat, temp_dir)
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
            best = best_of_sweep(sweep)
            remove_flops_files(sweep, keep=best.flops_path)  # best's: histograms_best.png
            runs += sweep
            runs.append(best)
    return runs


def write_outputs(runs, arguments):
    """Writes table1.md, speedup.png, histograms and results.json; returns the folder."""
    stats = table1.device_run(runs).stats
    out_dir = pathlib.Path(arguments.out) / device_slug(stats["device"])
    out_dir.mkdir(parents=True, exist_ok=True)
    meta = {"commit": git_commit(), "repeat": arguments.repeat,
            "date": utc_now()}
    files.write_text(out_dir / "table1.md", table1.render_table1(runs, meta))
    plots.plot_speedup(table1.speedup_bars(runs), out_dir / "speedup.png", stats["device"])
    for role, name in (("paper", "histograms.png"), ("best", "histograms_best.png")):
        flops_files = [load_checked_flops(run.flops_path) for run in runs
                       if run.role == role and run.flops_path]
        if flops_files:
            title = f"Flops per work-item (Figure 7), {role} geometries: {stats['device']}"
            plots.plot_flops_histograms(flops_files, out_dir / name, log=True, title=title)
    results = {"meta": meta, "paper": PAPER, "runs": [run.to_json() for run in runs]}
    files.write_text(out_dir / "results.json", json.dumps(results, indent=2) + "\n")
    return out_dir


def load_checked_flops(path):
    """Returns flops.FlopsFile for path, warning where its sidecar disagrees."""
    flops_file = flops.load_flops(path)
    for problem in flops.sidecar_mismatches(flops_file):
        print(f"warning: {path.name}.json: {problem}", file=sys.stderr)
    return flops_file


# --replot: the report redrawn from a stored results.json, without running rtcl.
RUN_ROLES = ("serial", "reference", "paper", "sweep", "best")
KEPT_FIGURES = ("histograms.png", "histograms_best.png")  # need the .npy files


def read_results(path):
    """Returns the object stored in results.json at path; ValueError if unreadable."""
    try:
        text = path.read_text(encoding="utf-8")
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
    return Run(item["role"], item["kernel"], item.get("workgroup"), item.get("groups"),
               item["command"], stats, batch=item.get("batch"))


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


def replot(out_dir):
    """Rewrites out_dir's table1.md and speedup.png from its results.json.

    Runs no rtcl.  Returns the lines to print: which figures were kept as they
    are (the histograms need the per-work-item .npy files, which are not stored).
    Nothing is written when results.json is missing or malformed (ValueError).
    """
    out_dir = pathlib.Path(out_dir)
    meta, stored = load_results(out_dir / "results.json")
    runs = best_rows_from_sweep(stored)
    meta = dict(meta, regenerated={"date": utc_now(), "commit": git_commit()})
    text = table1.render_table1(runs, meta)
    device = table1.device_run(runs).stats["device"]
    plots.plot_speedup(table1.speedup_bars(runs), out_dir / "speedup.png", device)
    files.write_text(out_dir / "table1.md", text)
    notes = [f"rewrote {out_dir / 'table1.md'} and {out_dir / 'speedup.png'}"]
    kept = [name for name in KEPT_FIGURES if (out_dir / name).exists()]
    if kept:
        notes.append(f"kept {', '.join(kept)} as they are (results.json holds no "
                     "per-work-item flops)")
    changed = changed_best_geometries(stored, runs)
    if changed and "histograms_best.png" in kept:
        notes.append("histograms_best.png shows the old best geometries: "
                     + ", ".join(changed))
    return notes
