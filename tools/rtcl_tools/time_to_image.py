"""Whole-process time to image, rtcl against POV-Ray 3.7 (issue 12 item 3):
tools/time_to_image.py is the command line; this is what it runs and parses."""

import os
import re
import resource
import statistics
import subprocess
import time

from . import povray_run

# The parts of rtcl's -v line "rtcl: time: ...", in its order.
BREAKDOWN_PARTS = ["device set-up", "scene and upload", "build", "kernels", "read-back",
                   "counting run", "encoding and writing", "total"]
PART = re.compile(r"(%s) ([0-9]+(?:\.[0-9]+)?) ms( \(cached\))?" %
                  "|".join(re.escape(p) for p in BREAKDOWN_PARTS))


# A program failed, is missing or printed nothing usable; the message says which.
RunError = povray_run.RunError


def rtcl_command(rtcl, scene, size, output, verbose=False):
    """A plain render with the default kernel, written as linear 8-bit values
    (--encoding linear, POV-Ray's File_Gamma 1.0)."""
    return [rtcl, "-s", scene, "--size", "%dx%d" % size, "--encoding", "linear", "-o", output,
            "-v" if verbose else "-q"]


def parse_breakdown(stderr):
    """The parts of rtcl's "rtcl: time:" line as {part: ms}, with "build_cached"."""
    lines = [line for line in stderr.splitlines() if line.startswith("rtcl: time: ")]
    if len(lines) != 1:
        raise RunError("rtcl -v printed %d \"rtcl: time:\" lines, expected 1" % len(lines))
    parts = {m.group(1): float(m.group(2)) for m in PART.finditer(lines[0])}
    missing = [p for p in BREAKDOWN_PARTS if p not in parts]
    if missing:
        raise RunError("rtcl's time line lacks %s: %s" % (", ".join(missing), lines[0]))
    parts["build_cached"] = " ms (cached)" in lines[0]
    return parts


def children_cpu():
    """User and system CPU seconds of the waited-for children so far."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def time_once(cmd, cwd, output, env=None):
    """Runs cmd in cwd; returns (wall seconds, CPU seconds, stderr). The
    output file must appear (it is removed first). The CPU time (user and
    system, every thread) hardly depends on what else the machine runs; the
    wall time does."""
    path = os.path.join(cwd, output)
    if os.path.exists(path):
        os.remove(path)
    cpu = children_cpu()
    start = time.perf_counter()
    try:
        done = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, errors="replace",
                              env=env)
    except OSError as e:
        raise RunError("cannot run %s: %s" % (cmd[0], e.strerror or e))
    wall = time.perf_counter() - start
    if done.returncode != 0 or not os.path.exists(path):
        text = (done.stderr.strip() or done.stdout.strip() or "no output").splitlines()
        raise RunError("%s failed (exit %d): %s" % (os.path.basename(cmd[0]), done.returncode,
                                                    text[-1] if text else "no output"))
    return wall, children_cpu() - cpu, done.stderr


def interleaved(jobs, runs):
    """Runs every job (name, function) runs times, alternating their order
    from round to round, so that a slow spell of the machine hits both;
    returns {name: [result, ...]}."""
    results = {name: [] for name, _ in jobs}
    for i in range(runs):
        order = jobs if i % 2 == 0 else list(reversed(jobs))
        for name, run in order:
            results[name].append(run())
    return results


def cpu_model():
    """lscpu's "Model name", or None."""
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, timeout=60).stdout
    except OSError:
        return None
    m = re.search(r"^Model name:\s*(.+)$", out, re.M)
    return m.group(1).strip() if m else None


def rtcl_device(rtcl, cwd):
    """The device a plain render uses, from rtcl -v's "platform P, device D:" line."""
    try:
        done = subprocess.run([rtcl, "--size", "4x4", "-o", "probe.ppm", "-v"], cwd=cwd,
                              capture_output=True, text=True, errors="replace")
    except OSError as e:
        raise RunError("cannot run %s: %s" % (rtcl, e.strerror or e))
    for line in done.stderr.splitlines():
        m = re.match(r"rtcl: platform \d+, device \d+: (.+)$", line)
        if m:
            return m.group(1)
    raise RunError("rtcl -v names no device (exit %d): %s" % (
        done.returncode, done.stderr.strip().splitlines()[-1:] or "no output"))


def summary(values):
    return "median %.3f s, min %.3f s, max %.3f s (%d runs)" % (
        statistics.median(values), min(values), max(values), len(values))


def format_breakdown(parts):
    """rtcl's breakdown as one line, in ms."""
    items = []
    for part in BREAKDOWN_PARTS:
        cached = " (cached)" if part == "build" and parts.get("build_cached") else ""
        items.append("%s %.1f%s" % (part, parts[part], cached))
    return ", ".join(items) + " ms"


def median_breakdown(breakdowns):
    """The median of each part over several -v runs."""
    parts = {p: statistics.median(b[p] for b in breakdowns) for p in BREAKDOWN_PARTS}
    parts["build_cached"] = all(b["build_cached"] for b in breakdowns)
    return parts


def ratio_verdict(rtcl_s, povray_s, target):
    ratio = rtcl_s / povray_s
    return ratio, "met" if ratio <= target else "missed"


def povray_command(exe, size, threads):
    return povray_run.command(exe, size, threads, "render.png")
