"""Ctrl-C, SIGTERM and SIGHUP end every tool the same way: one line, no traceback.

A command's main() is wrapped by @interruptible.  Inside it the three signals raise
Interrupted (a KeyboardInterrupt), so that every `with` block unwinds as after an
error: a temporary folder (tempfile.TemporaryDirectory) is removed, an rtcl that
subprocess.run waits for is killed, and the atomic writers (files.py) leave no
partial file.  A second signal while that happens is ignored, lest it cut the
clean-up short.  The tool then prints '<program>: interrupted (SIGTERM)' and exits
with 128 + the signal's number (130 for Ctrl-C, 143 for SIGTERM), as a shell
reports a program the signal ended.  A command that has more to say (what it kept,
how to resume) catches Interrupted itself and uses exit_status().
"""

import contextlib
import functools
import signal
import sys

from . import files
from .usage import program_name

SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class Interrupted(KeyboardInterrupt):
    """The tool was asked to stop by signal signum."""

    def __init__(self, signum=signal.SIGINT):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum


def exit_status(error):
    """Returns 128 + the signal's number for an Interrupted (or a plain Ctrl-C)."""
    return 128 + int(getattr(error, "signum", signal.SIGINT))


def signal_name(error):
    return signal.Signals(getattr(error, "signum", signal.SIGINT)).name


@contextlib.contextmanager
def signals_raise():
    """Inside the block, SIGINT, SIGTERM and SIGHUP raise Interrupted once; later
    ones are ignored while the block unwinds.  Outside the main thread (where
    Python allows no handlers) the block runs as it is."""
    raised = False

    def handler(signum, _frame):
        nonlocal raised
        if not raised:
            raised = True
            raise Interrupted(signum)

    try:
        previous = {number: signal.signal(number, handler) for number in SIGNALS}
    except ValueError:   # not the main thread
        yield
        return
    try:
        yield
    finally:
        for number, action in previous.items():
            signal.signal(number, action)


def interruptible(main):
    """Wraps a command's main(argv): signals become Interrupted, and one that the
    command does not catch ends it with one line and status 128 + the signal.  The
    inputs the command registered (files.reading) are its own: forgotten when it
    returns, so that a test calling several commands in one process sees each
    one's alone."""
    @functools.wraps(main)
    def wrapper(argv=None):
        try:
            with signals_raise(), files.inputs_forgotten():
                return main(argv)
        except KeyboardInterrupt as error:
            print(f"\n{program_name()}: interrupted ({signal_name(error)})", file=sys.stderr)
            return exit_status(error)
    return wrapper
