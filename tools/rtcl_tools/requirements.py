"""The tools' third-party modules: a missing one is one line, not a traceback.

A command module calls require() before it imports what needs numpy (at its
top), or in its main() before it draws with matplotlib (so that --help works
without it), e.g. require("matplotlib") in rtcl-flops-hist.  The line names the
Python that lacks the module and the command that installs it: from a checkout
`make deps` (Debian's packages for /usr/bin/python3, which tools/NAME.py then finds:
checkout.py), installed `apt-get install ...`; or pip for the Python that ran.
"""

import importlib
import sys

from .usage import program_name

# module: (its pip package, its Debian package)
PACKAGES = {
    "numpy": ("numpy", "python3-numpy"),
    "matplotlib": ("matplotlib", "python3-matplotlib"),
    "PIL": ("pillow", "python3-pil"),
}
# The Python that `make deps` gives the packages to (the Makefile's PYTHON).
SYSTEM_PYTHON = "/usr/bin/python3"


def missing_modules(*names):
    """Returns those of names that cannot be imported."""
    missing = []
    for name in names:
        try:
            importlib.import_module(name)
        except ImportError:
            missing.append(name)
    return missing


def joined(names):
    """Returns 'a', 'a and b' or 'a, b and c'."""
    names = list(names)
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]


def install_command(missing, python=None, checkout=None):
    """Returns the commands that install the missing modules: `make deps` in a
    checkout (Debian's packages, for /usr/bin/python3), else apt-get; or pip for
    python (default: the running one)."""
    if checkout is None:
        from .locations import in_source_tree
        checkout = in_source_tree()
    python = python or sys.executable or "python3"
    debian = " ".join(PACKAGES.get(name, (name, "python3-" + name.lower()))[1]
                      for name in missing)
    pip = " ".join(PACKAGES.get(name, (name,))[0] for name in missing)
    system = (f"`make deps` (Debian's {debian} for {SYSTEM_PYTHON}, which tools/NAME.py "
              "then uses)" if checkout else f"`apt-get install {debian}` (for {SYSTEM_PYTHON})")
    return f"{system}, or `{python} -m pip install {pip}`"


def requirement_message(program, missing, python=None, tried=(), checkout=None):
    """Returns 'PROGRAM: needs numpy, which PYTHON lacks: INSTALL COMMAND' for the
    missing names (tried: the other Pythons that lack them too)."""
    python = python or sys.executable or "python3"
    others = f", as do {', '.join(tried)}" if tried else ""
    return (f"{program}: needs {joined(missing)}, which {python} lacks{others}: "
            f"{install_command(missing, python, checkout)}")


def require(*names):
    """Exits with status 1 and one line on stderr when a module of names is missing.

    Called by a command module (the program's own code, never library code),
    before the first import or use of the module."""
    missing = missing_modules(*names)
    if missing:
        print(requirement_message(program_name(), missing), file=sys.stderr)
        sys.exit(1)
