"""How the tools write figures down: numbers, markdown tables, CSV, folder names."""

import csv
import datetime
import io
import math
import os
import pathlib
import re
import subprocess

ROOT = pathlib.Path(__file__).resolve().parent.parent.parent   # the rtcl checkout


def format_number(value, digits=1, suffix=""):
    """Returns value with digits decimals (and suffix), or '–' when unknown."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "–"
    return f"{value:,.{digits}f}{suffix}"


def format_percent(fraction):
    return "–" if fraction is None else f"{100 * fraction:.2f}%"


def markdown_table(header, rows):
    """Returns a markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(str(cell) for cell in row) + " |" for row in rows]
    return "\n".join(lines)


def to_csv(columns, rows):
    """Returns rows (dicts) as CSV text with the given columns."""
    stream = io.StringIO()
    writer = csv.DictWriter(stream, fieldnames=columns, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({key: "" if value is None else value for key, value in row.items()})
    return stream.getvalue()


def one_line(error):
    """Returns the message of error on one line (numpy's may span several); an
    OSError that names a file as 'FILE: REASON', without Python's [Errno N]."""
    if isinstance(error, OSError) and error.filename is not None and error.strerror:
        return " ".join(f"{error.filename}: {error.strerror}".split())
    return " ".join(str(error).split())


def utc_now():
    """Returns the date and time for a results header, e.g. '2030-01-01 00:00 UTC'."""
    return datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")


def device_slug(device_name):
    """Returns a folder name for a device, e.g. 'nvidia-h100-80gb-hbm3'.

    The platform in trailing parentheses is dropped.  PoCL names its CPU devices
    '<driver>-<llvm cpu>-<model>' (e.g. 'pthread-skylake-avx512-AMD EPYC'): those
    become 'pocl-<model>' (e.g. 'pocl-amd-epyc').
    """
    name = re.sub(r"\s*\([^()]*\)\s*$", "", device_name).strip() or device_name
    platform = device_name[len(name):]
    if "Portable Computing Language" in platform or re.match(r"(pthread|cpu|basic)-", name):
        parts = name.split("-")
        model_at = next((i for i, part in enumerate(parts) if re.search(r"[A-Z]", part)),
                        len(parts) - 1)
        name = "pocl " + "-".join(parts[model_at:])
    slug = re.sub(r"[^a-z0-9]+", "-", name.lower()).strip("-")
    return slug[:64].rstrip("-") or "unknown-device"


BUILT_IN_SCENE = "paper60"


def scene_stem(scene):
    """Returns the name a results folder gives a scene: its file's stem ('lake-10' for
    /tmp/lake/lake-10.json), 'paper60' for None (rtcl's built-in scene) or for the
    name rtcl's --stats gives that scene ('paper60.json (built-in)').  Characters other
    than letters, digits, '.', '_' and '-' become '-'."""
    if not scene:
        return BUILT_IN_SCENE
    name = re.sub(r"\s*\(built-in\)$", "", str(scene))
    stem = pathlib.PurePath(name).stem
    return re.sub(r"[^A-Za-z0-9._-]+", "-", stem).strip("-") or "scene"


def _git(*arguments):
    """Returns the output of git in the rtcl checkout; CalledProcessError or OSError."""
    return subprocess.run(["git", *arguments], cwd=ROOT, capture_output=True, text=True,
                          check=True).stdout.strip()


def git_commit():
    """Returns the short commit of the rtcl checkout ('-dirty' if modified), or None.
    RTCL_COMMIT, when set, is returned instead: a copy of the tree whose git
    HEAD is stale (a GPU machine's) names the commit it was made from."""
    if os.environ.get("RTCL_COMMIT"):
        return os.environ["RTCL_COMMIT"]
    try:
        commit = _git("rev-parse", "--short", "HEAD")
        changes = _git("status", "--porcelain", "--untracked-files=no")
    except (OSError, subprocess.CalledProcessError):
        return None
    return commit + ("-dirty" if changes else "")


def git_describe():
    """Returns `git describe --always --dirty` of the rtcl checkout, or None."""
    try:
        return _git("describe", "--always", "--dirty") or None
    except (OSError, subprocess.CalledProcessError):
        return None
