"""tools/NAME.py from a checkout: the tool runs under a Python that has its modules.

`tools/NAME.py` runs under the python3 its #! line finds first on PATH (or the one
typed before it), which may lack numpy or matplotlib (a pyenv build, a fresh
virtual environment) while another Python has them: Debian's /usr/bin/python3,
which `make deps` gives python3-numpy and python3-matplotlib, and which the
Makefile and the installed rtcl-NAME commands use.  So every tools/NAME.py calls
python_with(its modules) before it imports its command: when the running Python
lacks one of them, the tool starts again (os.execv, the same arguments) under the
first Python that has them all, of $RTCL_PYTHON (when set, the only one tried),
/usr/bin/python3 and python3 on PATH; when none has the required ones, it stops at
once with one line naming them and the command that installs them.

Modules are looked up, not imported (importlib.util.find_spec: quick, and what
cannot be imported after all is the command's own one-line require()).  The
restarted tool finds RTCL_TOOLS_PYTHON in its environment and does not restart
again.  The installed commands never come here: their Python is fixed when they
are installed (make install's PYTHON, or pip's).
"""

import importlib.util
import os
import shutil
import subprocess
import sys

from .requirements import SYSTEM_PYTHON, requirement_message

# Set in the environment of a tool restarted under another Python.
RESTARTED = "RTCL_TOOLS_PYTHON"
# Finds the modules named after it (exit status 0) without importing them.
FIND_SPEC = ("import importlib.util, sys; "
             "sys.exit(0 if all(importlib.util.find_spec(m) for m in sys.argv[1:]) else 1)")


def lacks(names):
    """Returns those of names the running Python does not find."""
    return [name for name in names if importlib.util.find_spec(name) is None]


def candidates():
    """Returns the other Pythons to try, in order, without the running one.  They
    are told apart by path, not by the program they run: a virtual environment's
    python is a link to its base Python's, with other modules."""
    given = os.environ.get("RTCL_PYTHON")
    names = [given] if given else [SYSTEM_PYTHON, shutil.which("python3")]
    running = os.path.abspath(sys.executable or "")
    found = []
    for name in names:
        if name and os.access(name, os.X_OK) and os.path.abspath(name) != running \
                and os.path.abspath(name) not in found:
            found.append(os.path.abspath(name))
    return found


def has_modules(python, names):
    """Whether python finds every module of names."""
    try:
        return subprocess.run([python, "-c", FIND_SPEC, *names], stdin=subprocess.DEVNULL,
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                              timeout=60).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


def python_with(required=(), wanted=()):
    """Makes sure the tool runs under a Python that has the required modules (and
    the wanted ones, which it can do without: experiments.py's matplotlib): returns
    when this one has them, else restarts the tool under another that has them,
    else exits with status 1 and one line (required) or returns (wanted)."""
    missing = lacks([*required, *wanted])
    if not missing or os.environ.get(RESTARTED):
        return
    tried = candidates()
    for python in tried:
        if has_modules(python, [*required, *wanted]):
            restart(python)
    must = lacks(required)
    if must:
        for python in tried:
            if has_modules(python, required):
                restart(python)
        program = os.path.basename(sys.argv[0]) or "rtcl-tools"
        print(requirement_message(program, must, sys.executable, tried, checkout=True),
              file=sys.stderr)
        sys.exit(1)


def restart(python):
    """Runs this tool again under python, in this process (os.execv)."""
    os.environ[RESTARTED] = python
    sys.stdout.flush()
    sys.stderr.flush()
    os.execv(python, [python, sys.argv[0], *sys.argv[1:]])
