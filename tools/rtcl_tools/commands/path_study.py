"""The study of schedules on paths (issue 41): tables and the path-length figure
from a batch's --stats files.

Reads a folder of rtcl --stats files named SCENE__SCHEDULE__rROUND.json (one
timed run, `-r N`, of a schedule on a scene in a round; the runs of one round
may carry a counting run too: --flops, so its figures are in the same file)
and SCENE__SCHEDULE__counted.json (a counting run made apart, whose time is
not used: run.sh's COUNT_ONLY=1),
and, when present, mitsuba.jsonl: one JSON object a line, {"scene", "form"
("megakernel" or "wavefront"), "ms", "width", "height", "spp"}, Mitsuba 3's
times on the same scenes (docs/results/h100-paths-study/pt_mitsuba.py writes
it; a record with "approximate" says how its scene differs from rtcl's, and
its "approximate_label", where given, labels its row; else "approximate BSDF"). Writes into the output folder (the input folder by default):

  paths.md          per scene: M paths/s per schedule; its time at 100 % SIMD,
                    lost to idle lanes and lost elsewhere (the Whitted study's
                    bounds, docs/RENDERING.md "Bounds on a kernel's time", with
                    the SIMD efficiency of all three phases, intersection,
                    traversal and shading, where measured); the SIMD efficiency
                    per phase; the live paths per bounce and the path lengths
                    (RENDERING.md, "Paths per bounce"); Mitsuba 3's forms beside
                    rtcl's schedules
  paths.json        the same numbers
  path_lengths.png  the share of paths by length in segments, one panel per
                    scene: the paper's per-thread histogram for paths, and
                    below it the share of paths live at each bounce (needs
                    matplotlib; left out, with a line, without it)

A schedule's time is the median over its rounds of each run's kernel_ms (itself
the median of its -r launches); "rounds" gives their spread.

    rtcl-path-study results/ -o results/ --peak-gflops 66900

A folder without such files, a file that is not a --stats file, or two files
that disagree on a scene's image size or samples is an error: one line on
stderr, exit status 1, nothing written.
"""

import argparse
import json
import os
import re
import statistics
import sys

from .. import files
from ..interrupts import interruptible
from ..peak import find_peak, is_cpu_device, read_cpuinfo
from ..report import format_number, format_percent, markdown_table, one_line
from ..usage import add_update_committed, program_name, report_error

NAME = re.compile(r"^(?P<scene>[A-Za-z0-9_.-]+?)__(?P<schedule>[A-Za-z0-9_.-]+)"
                  r"__(?:r(?P<round>\d+)|(?P<counted>counted))\.json$")
# Schedules in the order the tables list them; others follow by name.
ORDER = ("serial", "naive", "cyclic", "dynamic", "persistent", "persistent-regen-item",
         "persistent-regen-group", "persistent-regen-subgroup", "wavefront",
         "wavefront-bounce", "wavefront-stages")
PHASES = (("intersect", "intersection"), ("traversal", "traversal"), ("shade", "shading"),
          ("all", "all three"))


class StudyError(Exception):
    """Input the study cannot use."""


def parse_arguments(argv):
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0],
        epilog=__doc__.split("\n\n", 1)[1], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("folder", help="the batch's --stats files (SCENE__SCHEDULE__rN.json)")
    parser.add_argument("-o", "--output-dir", "--out", dest="output_dir", metavar="DIR",
                        help="where to write (default: the input folder)")
    parser.add_argument("--peak-gflops", type=float, metavar="X",
                        help="the device's FP32 peak (default: tools/rtcl_tools/peak.py's)")
    parser.add_argument("--fma-units", type=int, metavar="N",
                        help="FMA units per CPU core, for a CPU's peak")
    add_update_committed(parser)
    return parser.parse_args(argv)


def schedule_key(name):
    return (ORDER.index(name), name) if name in ORDER else (len(ORDER), name)


def read_runs(folder):
    """Returns {scene: {schedule: [stats, ...] by round}} from the folder."""
    runs = {}
    try:
        names = sorted(os.listdir(folder))
    except OSError as error:
        raise StudyError(f"{folder}: {error.strerror}") from None
    for name in names:
        match = NAME.match(name)
        if not match:
            continue
        path = os.path.join(folder, name)
        try:
            with open(path, encoding="utf-8") as f:
                stats = json.load(f)
        except (OSError, ValueError) as error:
            raise StudyError(f"{path}: not a --stats file ({one_line(error)})") from None
        if not isinstance(stats, dict) or "kernel_ms" not in stats:
            raise StudyError(f"{path}: not a --stats file (no kernel_ms)")
        stats["_file"] = name
        # A "counted" file (run.sh's COUNT_ONLY=1: a counting run of another
        # call) gives counts, never a time.
        stats["_round"] = int(match["round"]) if match["round"] else None
        runs.setdefault(match["scene"], {}).setdefault(match["schedule"], []).append(stats)
    if not runs:
        raise StudyError(f"{folder}: no --stats files named SCENE__SCHEDULE__rN.json")
    return runs


def read_mitsuba(folder):
    """Returns {scene: {form: record}} from mitsuba.jsonl, {} without one."""
    path = os.path.join(folder, "mitsuba.jsonl")
    found = {}
    if not os.path.exists(path):
        return found
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if not line.strip():
                continue
            try:
                record = json.loads(line)
                found.setdefault(record["scene"], {})[record["form"]] = record
            except (ValueError, KeyError, TypeError):
                raise StudyError(f"{path}:{number}: not a Mitsuba record") from None
    return found


def paths_of(stats):
    """Returns the samples traced: width x height x samples done."""
    return stats["width"] * stats["height"] * stats.get("samples_done", stats.get("samples", 1))


def counted(stats_list):
    """Returns the first run of a schedule that carries a counting run (a timed
    round's before a "counted" file's), or None."""
    for stats in sorted(stats_list, key=lambda s: (s["_round"] is None, s["_round"] or 0)):
        if "total_flops" in stats:
            return stats
    return None


def simd_for_bound(stats):
    """(efficiency, source): the measured efficiency of all three phases under
    the path integrator (of both, intersection and traversal, otherwise), else
    the model's, else (None, None)."""
    measured = stats.get("simd_efficiency_measured")
    if isinstance(measured, dict):
        for key in ("all", "both"):
            if measured.get(key) is not None:
                return measured[key], f"measured, {'all three phases' if key == 'all' else 'both'}"
    if stats.get("simd_efficiency_model") is not None:
        return stats["simd_efficiency_model"], "modelled"
    return None, None


def ratio(a, b):
    return a / b if a and b else None


def schedule_rows(scene_runs, peak_gflops, cpu):
    """Returns the numbers of each schedule of a scene, in table order."""
    rows = []
    sizes = {(s["width"], s["height"], s.get("samples_done", s.get("samples")))
             for runs in scene_runs.values() for s in runs}
    if len(sizes) > 1:
        raise StudyError(f"the runs disagree on the image size or samples: {sorted(sizes)}")
    for schedule in sorted(scene_runs, key=schedule_key):
        runs = scene_runs[schedule]
        timed = sorted((s for s in runs if s["_round"] is not None), key=lambda s: s["_round"])
        if not timed:
            continue                            # counted, never timed: no row
        times = [s["kernel_ms"] for s in timed]
        ms = statistics.median(times)
        count = counted(runs)
        row = {"schedule": schedule, "kernel": runs[0].get("kernel"), "ms": ms,
               "rounds_ms": times, "mpaths_per_s": paths_of(runs[0]) / ms / 1e3,
               "simd": None, "simd_source": None, "at_100_simd_ms": None,
               "flop_peak_ms": None, "lost_to_idle_lanes": None, "lost_elsewhere": None,
               "gflop": None, "simd_phases": None, "paths": None, "cpu": cpu}
        if count:
            row["gflop"] = count.get("gflop")
            row["paths"] = count.get("paths")
            measured = count.get("simd_efficiency_measured")
            row["simd_phases"] = measured
            peak_ms = 1e3 * row["gflop"] / peak_gflops if row["gflop"] and peak_gflops else None
            row["flop_peak_ms"] = peak_ms
            if not cpu:
                efficiency, source = simd_for_bound(count)
                row["simd"], row["simd_source"] = efficiency, source
                if efficiency is not None:
                    row["at_100_simd_ms"] = ms * efficiency
                    row["lost_to_idle_lanes"] = ratio(ms, row["at_100_simd_ms"])
                    row["lost_elsewhere"] = ratio(row["at_100_simd_ms"], peak_ms)
            else:
                row["lost_elsewhere"] = ratio(ms, peak_ms)
        rows.append(row)
    return rows


def spread(times):
    if len(times) < 2:
        return format_number(times[0], 2)
    return f"{format_number(min(times), 2)}–{format_number(max(times), 2)}"


def speed_table(rows, mitsuba, naive_ms):
    header = ("schedule", "time ms", "rounds", "M paths/s", "vs naive", "SIMD efficiency",
              "at 100 % SIMD ms", "flop-peak bound ms", "lost to idle lanes", "lost elsewhere")
    cells = []
    for r in rows:
        simd = (f"{format_percent(r['simd'])} ({r['simd_source']})" if r["simd_source"]
                else "does not apply (CPU)" if r["cpu"] else "–")
        cells.append((r["schedule"], format_number(r["ms"], 2), spread(r["rounds_ms"]),
                      format_number(r["mpaths_per_s"], 1),
                      format_number(ratio(naive_ms, r["ms"]), 2, "×"), simd,
                      format_number(r["at_100_simd_ms"], 2), format_number(r["flop_peak_ms"], 3),
                      format_number(r["lost_to_idle_lanes"], 2, "×"),
                      format_number(r["lost_elsewhere"], 1, "×")))
    for form in ("megakernel", "wavefront"):
        if form in mitsuba:
            m = mitsuba[form]
            label = f"Mitsuba 3 {form}" + (
                f" ({m.get('approximate_label', 'approximate BSDF')})" if m.get("approximate")
                else "")
            cells.append((label, format_number(m["ms"], 2), "–",
                          format_number(m["width"] * m["height"] * m["spp"] / m["ms"] / 1e3, 1),
                          format_number(ratio(naive_ms, m["ms"]), 2, "×"), "–", "–", "–", "–",
                          "–"))
    return markdown_table(header, cells)


def phase_table(rows):
    shown = [r for r in rows if isinstance(r["simd_phases"], dict)]
    if not shown:
        return None
    return markdown_table(("schedule",) + tuple(label for _, label in PHASES),
                          [(r["schedule"],) + tuple(format_percent(r["simd_phases"].get(key))
                                                    for key, _ in PHASES) for r in shown])


def bounce_lines(rows):
    """The paths per bounce and by length, from the counting runs, which must agree
    (every kernel counts the same paths)."""
    counts = [(r["schedule"], r["paths"]) for r in rows if r["paths"]]
    if not counts:
        return ["No counting run (--flops): no paths per bounce."]
    schedule, paths = counts[0]
    differ = [name for name, other in counts[1:] if other != paths]
    total = paths["count"]
    lines = [f"{total:,} paths, {paths['mean_length']:.3f} segments each on average, at most "
             f"{paths['max_length']} (the counting run of {schedule}"
             + (f"; the same in {', '.join(n for n, _ in counts[1:])})" if len(counts) > 1
                and not differ else ")") + "."]
    if differ:
        lines.append(f"**The counting runs differ** from {schedule}'s in: {', '.join(differ)}.")
    live = paths["live_per_bounce"]
    hist = paths["length_histogram"]
    header = ("bounce b", "paths live (a segment b traced)", "share", "paths of b + 1 segments")
    cells = [(b, f"{n:,}", format_percent(n / total if total else None),
              f"{hist[b]:,}" + (" or more" if b == len(hist) - 1 else ""))
             for b, n in enumerate(live)]
    lines += ["", markdown_table(header, cells)]
    return lines


def scene_lines(scene, rows, mitsuba):
    naive = next((r["ms"] for r in rows if r["schedule"] == "naive"), None)
    lines = [f"## {scene}", ""]
    lines.append(speed_table(rows, mitsuba, naive))
    best = min(rows, key=lambda r: r["ms"])
    notes = [f"Fastest schedule: **{best['schedule']}**, {format_number(best['ms'], 2)} ms"
             + (f", {format_number(ratio(naive, best['ms']), 2, '×')} naive's" if naive else "")]
    if mitsuba:
        form, m = min(mitsuba.items(), key=lambda item: item[1]["ms"])
        approximate = next((r for r in mitsuba.values() if r.get("approximate")), None)
        if approximate and "approximate_label" in approximate:
            notes.append("Mitsuba renders a scene like this one, not the same: "
                         + approximate["approximate"])
        elif approximate:
            notes.append("Mitsuba's exact mapping failed on this GPU: "
                         + approximate["approximate"]
                         + " (a BSDF of like cost, not the same)")
        notes.append(f"Mitsuba 3's fastest form: {form}, {format_number(m['ms'], 2)} ms; "
                     f"rtcl's fastest / Mitsuba's fastest: "
                     f"**{format_number(ratio(m['ms'], best['ms']), 2, '×')}**")
    lines += [""] + [f"- {n}" for n in notes]
    table = phase_table(rows)
    if table:
        lines += ["", "SIMD efficiency measured per phase (counting runs):", "", table]
    lines += ["", "Paths per bounce:", "", *bounce_lines(rows), ""]
    return lines


def plot_lengths(study, path):
    """The share of paths by length (top row) and the share of paths live at
    each bounce (bottom row), a column per scene."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    scenes = [(scene, rows) for scene, rows in study.items()
              if any(r["paths"] for r in rows)]
    if not scenes:
        return False
    fig, axes = plt.subplots(2, len(scenes), figsize=(3.6 * len(scenes), 5.8), squeeze=False)
    for column, (scene, rows) in enumerate(scenes):
        paths = next(r["paths"] for r in rows if r["paths"])
        hist = paths["length_histogram"][:max(paths["max_length"], 1)]
        total = paths["count"] or 1
        lengths = list(range(1, len(hist) + 1))
        top, bottom = axes[0][column], axes[1][column]
        top.bar(lengths, [100 * n / total for n in hist], color="#4878a8")
        top.set_title(f"{scene}\nmean {paths['mean_length']:.2f}, max {paths['max_length']}",
                      fontsize=9)
        top.set_xlabel("path length (segments)")
        top.set_xticks(lengths)
        top.grid(axis="y", alpha=0.3)
        live = paths["live_per_bounce"]
        bottom.plot(range(len(live)), [100 * n / total for n in live], "o-", color="#c8642a")
        bottom.set_xlabel("bounce b (segment b traced)")
        bottom.set_xticks(range(len(live)))
        bottom.set_ylim(0, 105)
        bottom.grid(alpha=0.3)
    axes[0][0].set_ylabel("% of paths")
    axes[1][0].set_ylabel("% of paths live")
    fig.tight_layout()
    files.save_figure(fig, path, "png", dpi=110)
    plt.close(fig)
    return True


def study_document(runs, mitsuba, peak):
    cpu = is_cpu_device(next(iter(next(iter(runs.values())).values()))[0].get("device", ""))
    study = {}
    for scene in sorted(runs):
        try:
            study[scene] = schedule_rows(runs[scene], peak.gflops, cpu)
        except StudyError as error:
            raise StudyError(f"{scene}: {error}") from None
    any_stats = next(iter(next(iter(runs.values())).values()))[0]
    lines = ["# Schedules on paths (issue 41)", "",
             f"Device: {any_stats.get('device', '?')}. FP32 peak: {peak.formula}.", "",
             "Per scene and schedule: the kernel time (the median over the rounds of each "
             "run's median of its launches), M paths/s = pixels × samples / time; where a "
             "counting run (--flops) measured it, the bounds of the Whitted study "
             "(docs/RENDERING.md, \"Bounds on a kernel's time\"): at 100 % SIMD = time × "
             "SIMD efficiency (measured: all three phases, intersection, traversal and "
             "shading steps; else modelled), flop-peak bound = counted GFLOP / FP32 peak, "
             "lost to idle lanes = time / at 100 % SIMD, lost elsewhere = at 100 % SIMD / "
             "flop-peak bound."]
    if cpu:
        lines += ["", "On a CPU (PoCL) the SIMD columns do not apply (no warps in "
                  "lock-step): lost elsewhere is time / flop-peak bound."]
    lines.append("")
    for scene, rows in study.items():
        if rows:
            lines += scene_lines(scene, rows, mitsuba.get(scene, {}))
        else:
            lines += [f"## {scene}", "", "Counting runs only, no timed run.", ""]
    return study, "\n".join(lines)


@interruptible
def main(argv=None):
    args = parse_arguments(argv)
    out = args.output_dir or args.folder
    try:
        runs = read_runs(args.folder)
        mitsuba = read_mitsuba(args.folder)
        any_stats = next(iter(next(iter(runs.values())).values()))[0]
        peak = find_peak(any_stats, args, read_cpuinfo())
        study, text = study_document(runs, mitsuba, peak)
        with files.committed_files_allowed(args.update_committed):
            write_outputs(out, study, text, mitsuba, peak)
    except (StudyError, OSError, files.TrackedFileError) as error:
        return report_error(program_name(), one_line(error))
    return 0


def write_outputs(out, study, text, mitsuba, peak):
    """Writes paths.md, paths.json and the figure into out."""
    os.makedirs(out, exist_ok=True)
    files.write_text(os.path.join(out, "paths.md"), text + "\n")
    numbers = {scene: [{k: v for k, v in r.items()} for r in rows]
               for scene, rows in study.items()}
    files.write_text(os.path.join(out, "paths.json"),
                     json.dumps({"peak_gflops": peak.gflops, "peak": peak.formula,
                                 "scenes": numbers, "mitsuba": mitsuba}, indent=1) + "\n")
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        print(f"{program_name()}: matplotlib is missing: path_lengths.png not drawn",
              file=sys.stderr)
    else:
        if plot_lengths(study, os.path.join(out, "path_lengths.png")):
            print(os.path.join(out, "path_lengths.png"))
    print(os.path.join(out, "paths.md"))


if __name__ == "__main__":
    sys.exit(main())
