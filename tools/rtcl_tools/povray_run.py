"""Running POV-Ray 3.7 on SDL text and reading its own timings."""

import os
import re
import statistics
import subprocess
import tempfile
import time

from . import files

class RunError(Exception):
    """POV-Ray is missing, failed or printed nothing usable; the message says which."""


def povray_version(exe):
    try:
        done = subprocess.run([exe, "--version"], capture_output=True, text=True, timeout=60)
    except OSError as e:
        raise RunError("cannot run %s: %s" % (exe, e.strerror or e))
    for line in (done.stdout + "\n" + done.stderr).splitlines():
        if line.startswith("POV-Ray "):
            return line.strip()
    raise RunError("%s --version printed no POV-Ray version" % exe)


TRACE_TIME = re.compile(r"Trace Time:.*?\(([0-9.]+) seconds\)\s*\n\s*using (\d+) thread\(s\) "
                        r"with ([0-9.]+) CPU-seconds")


def povray_error(text):
    """The most telling line of POV-Ray's output after a failure."""
    lines = [l.strip() for l in text.splitlines() if l.strip()]
    for line in lines:
        if "error" in line.lower() and "configuration file" not in line:
            return line
    return lines[-1] if lines else "no output"


def command(exe, size, threads, out_name):
    """POV-Ray's command line for scene.pov in the working directory: one ray per
    pixel, no display, linear output (File_Gamma 1.0), PNG unless out_name is .ppm."""
    return [exe, "+Iscene.pov", "+O" + out_name, "+W%d" % size[0], "+H%d" % size[1],
            "-A", "+WT%d" % threads, "-D", "+FP" if out_name.endswith(".ppm") else "+FN",
            "File_Gamma=1.0"]


def render(exe, pov_text, size, threads, runs, image):
    """Render pov_text runs times; return (command, [(wall, trace, threads, cpu)])."""
    ext = ".ppm" if image and image.lower().endswith(".ppm") else ".png"
    results = []
    with tempfile.TemporaryDirectory(prefix="rtcl-povray-") as tmp:
        with open(os.path.join(tmp, "scene.pov"), "w", encoding="utf-8") as f:
            f.write(pov_text)
        out_name = "render" + ext
        cmd = command(exe, size, threads, out_name)
        for _ in range(runs):
            out_path = os.path.join(tmp, out_name)
            if os.path.exists(out_path):
                os.remove(out_path)
            start = time.perf_counter()
            done = subprocess.run(cmd, cwd=tmp, capture_output=True, text=True,
                                  errors="replace")
            wall = time.perf_counter() - start
            text = done.stdout + "\n" + done.stderr
            if done.returncode != 0 or not os.path.exists(out_path):
                raise RunError("povray failed (exit %d): %s" % (done.returncode, povray_error(text)))
            m = TRACE_TIME.search(text)
            if m:
                results.append((wall, float(m.group(1)), int(m.group(2)), float(m.group(3))))
            else:
                results.append((wall, None, None, None))
        if image:
            files.copy_file(os.path.join(tmp, out_name), image)
    return cmd, results


def summary(values):
    return "median %.3f s, min %.3f s, max %.3f s" % (statistics.median(values), min(values),
                                                       max(values))
