"""The FP32 peak of the benchmarked device: a GPU from a table, a CPU from its flags.

A peak that cannot be found is no reason to refuse a benchmark: it only fills the
"% of FP32 peak" column, which then stays empty, the table saying why.
"""

import dataclasses
import pathlib
import re

# GPUs whose FP32 peak is known: (pattern on the device name, part, FP32 lanes per
# compute unit, boost clock in GHz).  Matched in order: the first that matches.
GPU_PEAKS = (
    (r"H100.*PCIe", "NVIDIA H100 PCIe (GH100)", 128, 1.755),
    (r"H100.*NVL", "NVIDIA H100 NVL (GH100)", 128, 1.785),
    (r"H200.*NVL", None, None, None),               # its clock: not in the table
    (r"\bH100\b|\bH200\b", "NVIDIA H100/H200 SXM (GH100)", 128, 1.98),
    (r"\bA100\b", "NVIDIA A100 (GA100)", 64, 1.41),
)


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


def is_cpu_device(device):
    """Whether the OpenCL device named device is a CPU: PoCL's ('pthread-...',
    'cpu-...', '... (Portable Computing Language)')."""
    return bool("Portable Computing Language" in device
                or re.match(r"(pthread|cpu|basic)-", device))


# The /proc/cpuinfo fields a CPU's peak is computed from (kept in results.json, so
# that --replot --fma-units elsewhere can compute it again).
PEAK_FLAGS = ("avx512f", "avx2", "fma")


def peak_cpuinfo(cpuinfo):
    """Returns the fields of cpuinfo that cpu_peak reads, the flags cut to PEAK_FLAGS."""
    kept = {name: cpuinfo[name] for name in ("model name", "cpu cores", "siblings")
            if name in cpuinfo}
    kept["flags"] = " ".join(flag for flag in cpuinfo.get("flags", "").split()
                             if flag in PEAK_FLAGS)
    return kept


def find_peak(stats, arguments, cpuinfo):
    """Returns the Peak for the device of stats; its gflops None when unknown."""
    if arguments.peak_gflops:
        return Peak(arguments.peak_gflops,
                    f"given on the command line: --peak-gflops {arguments.peak_gflops:g}")
    device = stats["device"]
    units = stats.get("compute_units")
    if units:
        peak = gpu_peak(device, units)
        if peak:
            return peak
    if is_cpu_device(device) and cpuinfo:
        peak = cpu_peak(stats, cpuinfo, arguments.fma_units)
        if peak:
            return peak
        if simd_lanes(cpuinfo.get("flags", "")) and not arguments.fma_units:
            return Peak(None, f"unknown: the FP32 peak of {device} needs the FMA units per "
                              "core, which the CPU flags do not tell (--fma-units N: 1 for "
                              "AMD Zen 4, 2 for most Intel Xeon Gold/Platinum; or "
                              "--peak-gflops X)")
    return Peak(None, f"unknown: {device} is not in the built-in table (--peak-gflops X "
                      "gives it)")
