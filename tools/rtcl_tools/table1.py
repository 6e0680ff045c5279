"""Table 1 of the 2009 paper, ours beside the paper's, and Figure 6's speedups."""

from .paper import PAPER, PARALLEL_KERNELS, SWEEP_REPEAT
from .peak import is_cpu_device
from .report import BUILT_IN_SCENE, format_number, format_percent, markdown_table, scene_stem

TABLE_COLUMNS = ("Implementation", "work-group", "groups / threads", "time ms (median)",
                 "paper time", "GFLOP/s", "paper GFLOP/s", "parallel efficiency",
                 "paper efficiency", "SIMD efficiency measured", "SIMD efficiency modelled",
                 "work-items that traced pixels", "speedup over serial", "paper speedup",
                 "speedup over CPU reference")

# What a --stats file says where SIMD efficiency cannot be measured.
NOT_MEASURABLE = "not measurable on this device"


def simd_cells(stats):
    """Returns the (measured, modelled) SIMD efficiency cells of a --stats file
    (docs/RENDERING.md): measured as "intersection / traversal", "n/m" where the
    device does not let software see it, "–" where nothing was counted."""
    measured = stats.get("simd_efficiency_measured")
    if isinstance(measured, dict):
        measured_cell = (f"{format_percent(measured.get('intersect'))} / "
                         f"{format_percent(measured.get('traversal'))}")
    elif measured == NOT_MEASURABLE:
        measured_cell = "n/m"
    else:
        measured_cell = "–"
    return measured_cell, format_percent(stats.get("simd_efficiency_model"))


def used_items_cell(stats):
    """Returns "N of M": the work-items that traced at least one pixel (from the
    schedule map) of those launched; "–" without a schedule map."""
    used = stats.get("work_items_used")
    width, height = stats.get("global_size", [0, 0])
    if used is None or not width or not height:
        return "–"
    return f"{used:,} of {width * height:,}"


def simd_for_bound(stats):
    """Returns (SIMD efficiency, where it comes from) for a run's bound: the measured
    efficiency of both phases together (docs/RENDERING.md) where the device measured
    it, else the model; (None, None) where neither exists."""
    measured = stats.get("simd_efficiency_measured")
    if isinstance(measured, dict) and measured.get("both") is not None:
        return measured["both"], "measured"
    if stats.get("simd_efficiency_model") is not None:
        return stats["simd_efficiency_model"], "modelled"
    return None, None


def cpu_bound_row(run, peak_gflops):
    """Returns the bounds row of a run on a CPU, where SIMD efficiency (a GPU's warps
    of 32 in lock-step) does not apply: the flop-peak bound, and time / that bound
    as all that is lost."""
    stats = run.stats
    kernel_ms = stats["kernel_ms"]
    gflop = stats.get("gflop")
    peak_ms = 1e3 * gflop / peak_gflops if gflop and peak_gflops else None
    return (implementation_name(run), format_number(kernel_ms, 2), "does not apply (CPU)",
            "–", format_number(peak_ms, 3), "–",
            format_number(ratio(kernel_ms, peak_ms), 1, "×"),
            format_percent(ratio(peak_ms, kernel_ms)))


# Why a CPU's bounds leave SIMD efficiency out (bounds_lines).
CPU_SIMD_NOTE = ("On this CPU the SIMD columns do not apply: the modelled SIMD efficiency "
                 "assumes a GPU's warps of 32 work-items in lock-step, while PoCL runs a "
                 "work-group's work-items one after the other, or in a loop its compiler "
                 "vectorises to the CPU's own vector width (8 FP32 lanes with AVX2, 16 with "
                 "AVX-512) where it can, which rtcl does not measure. Only the flop-peak "
                 "bound applies: *lost elsewhere* is then time / flop-peak bound, "
                 "divergence included.")


def on_cpu(runs):
    """Whether the study's device (not the CPU reference) is a CPU (PoCL)."""
    return is_cpu_device(device_run(runs).stats.get("device", ""))


def bound_row(run, peak_gflops):
    """Returns the cells of one row of the bounds table (item 4 of issue 25, after
    Aila & Laine 2009): the time, the time at 100 % SIMD efficiency (time × SIMD
    efficiency), the counted-flop peak bound (GFLOP / FP32 peak) and the two
    factors between them: time / SIMD bound (lost to idle lanes) and SIMD bound /
    peak bound (everything else: memory, uncounted instructions, occupancy)."""
    stats = run.stats
    kernel_ms = stats["kernel_ms"]
    efficiency, source = simd_for_bound(stats)
    simd_ms = kernel_ms * efficiency if efficiency is not None else None
    gflop = stats.get("gflop")
    peak_ms = 1e3 * gflop / peak_gflops if gflop and peak_gflops else None
    return (implementation_name(run), format_number(kernel_ms, 2),
            f"{format_percent(efficiency)} ({source})" if source else "–",
            format_number(simd_ms, 2), format_number(peak_ms, 3),
            format_number(ratio(kernel_ms, simd_ms), 2, "×"),
            format_number(ratio(simd_ms, peak_ms), 1, "×"),
            format_percent(ratio(peak_ms, kernel_ms)))


def ratio(numerator, denominator):
    """Returns numerator / denominator, None when either is unknown or zero."""
    if not numerator or not denominator:
        return None
    return numerator / denominator


BOUND_COLUMNS = ("Implementation", "time ms", "SIMD efficiency", "at 100 % SIMD ms",
                 "flop-peak bound ms", "lost to idle lanes", "lost elsewhere",
                 "share of peak")


def bounds_lines(runs, peak):
    """Returns the "Bounds" section of table1.md: for each row of Table 1 but the CPU
    reference, where the kernel stands between the time it would take with every
    lane of every warp busy and the time its counted flops take at the FP32 peak."""
    shown = [run for run in table_runs(runs) if run.kernel != "reference"]
    peak_gflops = peak.get("gflops") if peak else None
    formula = peak.get("formula") if peak else "unknown (--peak-gflops X gives it)"
    if on_cpu(runs):
        return ["", "## Bounds", "", CPU_SIMD_NOTE, "", f"- FP32 peak: {formula}", "",
                markdown_table(BOUND_COLUMNS, [cpu_bound_row(run, peak_gflops)
                                               for run in shown])]
    return ["", "## Bounds", "",
            "Where each kernel stands between two lower bounds on its time (after Aila "
            "& Laine 2009): **at 100 % SIMD** = time × SIMD efficiency, the time "
            "if every lane of every warp-step were busy (measured: both phases, "
            "intersection and traversal steps, docs/RENDERING.md; else modelled); "
            "**flop-peak bound** = counted GFLOP / FP32 peak, the time if every lane "
            "did one counted flop (an FMA two) every cycle. time = flop-peak bound × "
            "lost elsewhere × lost to idle lanes: *lost to idle lanes* = time / at "
            "100 % SIMD, what divergence costs; *lost elsewhere* = at 100 % SIMD / "
            "flop-peak bound: memory waits, instructions the flop count leaves out "
            "(traversal's integer work, loads), too few work-items in flight. "
            "Share of peak = flop-peak bound / time.",
            "", f"- FP32 peak: {formula}", "",
            markdown_table(BOUND_COLUMNS, [bound_row(run, peak_gflops) for run in shown])]


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
            format_percent(paper.get("efficiency")), *simd_cells(stats), used_items_cell(stats),
            format_number(speedup(serial_ms, kernel_ms), 1),
            format_number(paper.get("speedup"), 0),
            format_number(speedup(reference_ms, kernel_ms), 2))


def table_runs(runs):
    """Returns the runs that Table 1 shows, in its order."""
    order = {"serial": 0, "reference": 1, "naive": 2, "cyclic": 3, "dynamic": 4,
             "persistent": 5, "wavefront": 6}
    shown = [run for run in runs if run.role != "sweep"]
    return sorted(shown, key=lambda run: (run.role == "best", order.get(run.kernel, 9)))


def device_run(runs):
    """Returns a run on the OpenCL device (not the CPU reference)."""
    return next(run for run in runs if run.kernel != "reference")


# How rays find what they hit, per --accel (the header's acceleration line).
ACCEL_TEXT = {"none": "every ray tests every sphere and triangle, the paper's brute force",
              "bvh": "rays traverse a BVH built on the host (issue 11 item 8: does the "
                     "paper's ranking hold when traversal diverges?)"}


def study_accel(runs, meta):
    """Returns the study's --accel: meta's, else the one rtcl's --stats name, else
    'none' (results.json files made before rtcl had a BVH: brute force)."""
    return meta.get("accel") or device_run(runs).stats.get("accel") or "none"


def study_suffix(runs, meta):
    """Returns ', --accel bvh, scene lake-10' for a study other than the paper's
    (--accel none on the built-in scene), '' for the paper's."""
    accel = study_accel(runs, meta)
    stem = meta.get("scene_stem") or scene_stem(device_run(runs).stats["scene"])
    if accel == "none" and stem == BUILT_IN_SCENE:
        return ""
    return f", --accel {accel}, scene {stem}"


def accel_line(runs, meta):
    accel = study_accel(runs, meta)
    line = f"- acceleration: `--accel {accel}`: {ACCEL_TEXT.get(accel, accel)}"
    if accel != "none" and any(run.kernel == "reference" for run in runs):
        line += "; the CPU reference has no BVH: it tests every object"
    return line


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
    lines = ["# Table 1 reproduced: rtcl on " + stats["device"] + study_suffix(runs, meta), "",
             f"- device: {stats['device']} ({stats.get('device_version', '')})",
             f"- driver: {stats.get('driver', '')}",
             f"- scene: {stats['scene']}, {stats['width']}x{stats['height']}, "
             f"max depth {stats['max_depth']}",
             accel_line(runs, meta),
             f"- rtcl {stats.get('rtcl_version', '?')}, commit {meta.get('commit') or 'unknown'}, "
             f"{meta['date']}",
             *regenerated_lines(meta),
             f"- times: median of {meta['repeat']} launches (sweep: {SWEEP_REPEAT}); the "
             "paper's are in seconds for 2000x2000 on the server Lincoln, ours in "
             "milliseconds",
             "- speedup over serial: our serial kernel is one work-item on the device; "
             "the paper's serial is a CPU program",
             *best_of_sweep_lines(runs), f"- {total_work_line(runs)}",
             *beyond_the_paper_lines(runs), "",
             markdown_table(TABLE_COLUMNS, [table_row(run, serial_ms, reference_ms)
                                            for run in table_runs(runs)]),
             *bounds_lines(runs, meta.get("peak"))]
    sweep = [run for run in runs if run.role == "sweep"]
    if sweep:
        lines += ["", "## Sweep", "",
                  markdown_table(("kernel", "work-group", "groups / threads", "time ms",
                                  "GFLOP/s", "parallel efficiency"),
                                 [sweep_row(run) for run in sweep])]
    lines += ["", "## Commands", "", "```"]
    lines += [run.command for run in runs if run.role != "best"]  # best: a sweep line
    lines += ["```", ""]
    return "\n".join(lines)


def regenerated_lines(meta):
    """Returns the header line of a table redrawn by experiments.py --replot, if it is one."""
    again = meta.get("regenerated")
    if not again:
        return []
    return [f"- regenerated on {again['date']} from the stored results.json (measured at "
            f"commit {meta.get('commit') or 'unknown'}, {meta['date']}) by the report code "
            f"of commit {again.get('commit') or 'unknown'} (`tools/experiments.py "
            "--replot`), without running rtcl: best-of-sweep rows taken from the stored "
            "sweep"]


def best_of_sweep_lines(runs):
    """Returns the header line that says where the best-of-sweep times come from."""
    if not any(run.role == "best" for run in runs):
        return []
    return [f"- best of sweep: the fastest entry of the kernel's sweep below, with that "
            f"entry's own time (median of {SWEEP_REPEAT} launches), not re-timed"]


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
    lines.append("- SIMD efficiency (docs/RENDERING.md): measured on NVIDIA devices in the "
                 "counting run (intersection steps / BVH traversal steps; n/m: not "
                 "measurable on this device), modelled from the flops per pixel and the "
                 "schedule map (warps of 32 in lock-step; – for the wavefront, whose "
                 "work-items take rays, and where nothing was counted); work-items that "
                 "traced pixels: from the schedule map, of those launched (on a CPU, "
                 "where a work-group's items run one after the other, the first items "
                 "of dynamic and persistent take most of the work: their low parallel "
                 "efficiency)" + ("; on this CPU the modelled column is a GPU's warp "
                                  "model, which does not apply (see Bounds)"
                                  if on_cpu(runs) else ""))
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
