"""The tools' third-party modules: a missing one is one line, not a traceback.

A command module calls require() before it imports what needs numpy (at its
top), or in its main() before it draws with matplotlib (so that --help works
without it), e.g. require("matplotlib") in rtcl-flops-hist.
"""

import importlib
import sys

from .usage import program_name

HOW_TO_INSTALL = {
    "numpy": "pip install numpy, or apt-get install python3-numpy",
    "matplotlib": "pip install matplotlib, or apt-get install python3-matplotlib",
    "PIL": "pip install pillow, or apt-get install python3-pil",
}


def missing_modules(*names):
    """Returns those of names that cannot be imported."""
    missing = []
    for name in names:
        try:
            importlib.import_module(name)
        except ImportError:
            missing.append(name)
    return missing


def requirement_message(program, missing):
    """Returns 'PROGRAM: needs numpy (pip install numpy, or ...)' for the missing names."""
    return f"{program}: needs " + "; ".join(
        f"{name} ({HOW_TO_INSTALL.get(name, 'pip install ' + name)})" for name in missing)


def require(*names):
    """Exits with status 1 and one line on stderr when a module of names is missing.

    Called by a command module (the program's own code, never library code),
    before the first import or use of the module."""
    missing = missing_modules(*names)
    if missing:
        print(requirement_message(program_name(), missing), file=sys.stderr)
        sys.exit(1)
