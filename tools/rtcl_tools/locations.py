"""Where the tools find things: the rtcl program, the source tree, the results folders.

The rtcl a tool runs, unless --rtcl names one: the rtcl that came with this copy of
the tools (beside the installed command: `make install` and `pip install` put
rtcl-bench and rtcl in one bin folder; or the built ./rtcl of the source tree that
tools/bench.py is part of), else `rtcl` on PATH, else ./rtcl in the current folder.

Results go where -o/--out says; by default to a new folder
rtcl-results/<name>-<YYYYmmdd-HHMMSS> under the current folder, never into
docs/results, which only --update-committed writes (`make results`).
"""

import datetime
import os
import pathlib
import shutil
import sys

# The rtcl checkout holding this package when it runs from a source tree (tools/
# beside host/); for an installed package, a folder without host/ or docs/.
SOURCE_ROOT = pathlib.Path(__file__).resolve().parent.parent.parent
DEFAULT_RESULTS = "rtcl-results"


class NotFound(Exception):
    """A program or folder the tool needs is not there (one line)."""


def in_source_tree():
    """Whether this package is tools/rtcl_tools of an rtcl checkout."""
    return (SOURCE_ROOT / "host").is_dir() and (SOURCE_ROOT / "tools" / "rtcl_tools").is_dir()


def is_program(path):
    return os.path.isfile(path) and os.access(path, os.X_OK)


def find_rtcl(given=None):
    """Returns the rtcl program to run: given (--rtcl) as it is, else the first of
    the rtcl beside the running command, the source tree's ./rtcl, rtcl on PATH,
    ./rtcl; NotFound, naming where it looked, when there is none."""
    if given:
        return given
    command_dir = pathlib.Path(sys.argv[0]).absolute().parent if sys.argv[0] else None
    candidates = []
    if command_dir is not None:
        candidates.append(command_dir / "rtcl")
    if in_source_tree():
        candidates.append(SOURCE_ROOT / "rtcl")
    for candidate in candidates:
        if is_program(candidate):
            return str(candidate)
    on_path = shutil.which("rtcl")
    if on_path:
        return on_path
    if is_program("rtcl"):
        return "./rtcl"
    looked = [str(candidate) for candidate in candidates] + ["PATH", "./rtcl"]
    raise NotFound(f"cannot find rtcl (looked at {', '.join(looked)}): build it with "
                   "make, or name it with --rtcl PROGRAM")


def committed_results():
    """Returns the source tree's docs/results, the folder of the committed results;
    NotFound outside a source tree (an installed copy has none)."""
    folder = SOURCE_ROOT / "docs" / "results"
    if not in_source_tree() or not folder.is_dir():
        raise NotFound("--update-committed writes into docs/results of the rtcl source "
                       "tree: run tools/NAME.py (or make results) from a checkout")
    return folder


def new_results_folder(name, parent=DEFAULT_RESULTS, now=None):
    """Makes and returns a new folder parent/<name>-<YYYYmmdd-HHMMSS> (a -2, -3, ...
    suffix when a run in the same second made one): never a folder with results."""
    stamp = (now or datetime.datetime.now()).strftime("%Y%m%d-%H%M%S")
    base = pathlib.Path(parent) / f"{name}-{stamp}"
    folder, number = base, 1
    while True:
        try:
            folder.mkdir(parents=True)
            return folder
        except FileExistsError:
            number += 1
            folder = base.with_name(f"{base.name}-{number}")
