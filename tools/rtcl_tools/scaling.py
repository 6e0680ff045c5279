"""The benchmark's scaling runs: one configuration at several image sizes and sphere
counts, time per megapixel and per megapixel x sphere, and least-squares checks of
linearity (scaling.csv, scaling.md)."""

import dataclasses
import math

from . import files, genscene
from .bench_plan import KERNEL_ORDER, groups_total
from .bench_report import figures, number
from .bench_run import BenchProgress, run_one
from .paper import GROUP_KERNELS
from .report import format_percent, markdown_table
from .runner import RtclFailed, describe, parse_pair
from .usage import UsageError, check_pair, check_positive_int

SCALING_SIZES = ("500x500", "1000x1000", "2000x2000", "3000x3000", "4000x4000")
SCALING_SPHERES = (60, 240, 600)
SCALING_SEED = 2009
SCALING_DEFAULT = ("dynamic", "8x8", None, None)   # kernel, work-group, groups, batch
SCALING_COLUMNS = ("spheres", "width", "height", "megapixels", "status", "reason",
                   "median_ms", "min_ms", "max_ms", "ms_per_megapixel",
                   "ms_per_megapixel_sphere", "gflop", "gflops", "mrays_per_s",
                   "rays_per_pixel", "parallel_efficiency", "repeat", "kernel_ms_all",
                   "scene", "command")


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
        try:
            scene = genscene.build_scene(count, SCALING_SEED, (2000, 2000),
                                         5 if depth is None else depth)
        except genscene.PlacementError as error:
            raise ValueError(f"genscene.py failed for {count} spheres: {error}") from None
        files.write_text(path, genscene.to_json(scene))
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
                     format_percent(row["parallel_efficiency"]), ""])
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
             markdown_table(
                 ("spheres", "size", "megapixels", "median ms", "ms / megapixel",
                  "ms / (megapixel × sphere)", "GFLOP", "rays/pixel",
                  "parallel efficiency", "note"), rows),
             "", "## Linearity (least squares)", "",
             "Linear in pixels, per sphere count: ms = intercept + slope × megapixels", "",
             markdown_table(("spheres",) + fit_header,
                                        [[str(count)] + fit_cells(fit, "ms/MP")
                                         for count, fit in by_spheres.items()]),
             "", "Linear in spheres, per size: ms = intercept + slope × spheres", "",
             markdown_table(("size",) + fit_header,
                                        [[size] + fit_cells(fit, "ms/sphere")
                                         for size, fit in by_size.items()]),
             "", "Every point: ms = intercept + slope × (megapixels × spheres)", "",
             markdown_table(fit_header, [fit_cells(overall, "ms/(MP·sphere)")]),
             "", "Every point against the counted work: ms = intercept + slope × GFLOP", "",
             markdown_table(fit_header, [fit_cells(by_work, "ms/GFLOP")]),
             "", "R² = 1 − (residual sum of squares) / (total sum of squares); the largest "
             "deviation is max |measured − fit| / measured over the points of the fit. "
             "Through two points a line fits exactly (R² = 1): the check needs three or "
             "more.", ""]
    return "\n".join(lines)
