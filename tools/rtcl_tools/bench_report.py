"""bench.csv and bench.md: one row per configuration, the derived figures, the table."""

from .bench_plan import KERNEL_ORDER, groups_total
from .paper import GROUP_KERNELS, PAPER
from .report import format_number, format_percent, markdown_table
from .runner import describe

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


def number(value, digits=2):
    """Returns value with digits decimals and thousands separators, '–' if unknown."""
    return format_number(value, digits)


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
        parts.append("paper geometry" if config.kernel in PAPER
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
             format_percent(efficiency), number(stats.get("gflop"), 3),
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
             markdown_table(
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
             markdown_table(TABLE_COLUMNS, [
                 table_row(c, peak.gflops, best.get(c.kernel) is c)
                 for c in sorted_for_table(configs)]), ""]
    return "\n".join(lines)
