"""Runs a program with its standard error on a pseudo-terminal, as a user's
terminal would be, to see rtcl's progress line (test_progress.py,
test_cli_spp.py)."""
import os
import pty
import subprocess


def on_terminal(command, cwd, timeout=120):
    """Runs command (a list) with stderr on a pseudo-terminal; returns (the
    completed process, stdout as text, what the terminal showed as bytes)."""
    controller, terminal = pty.openpty()
    try:
        result = subprocess.run(command, cwd=cwd, stdout=subprocess.PIPE, stderr=terminal,
                                text=True, timeout=timeout)
    finally:
        os.close(terminal)
    shown = b""
    try:
        while chunk := os.read(controller, 65536):
            shown += chunk
    except OSError:  # the terminal's other end is closed: all read
        pass
    os.close(controller)
    return result, shown
