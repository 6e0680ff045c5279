"""The tools' command lines: option checks (a bad option is one line on stderr and exit
status 2) and error reports in the form 'PROGRAM: error: MESSAGE'."""

import argparse
import os
import re
import sys


def program_name():
    """Returns the running command's name as its user typed it: rtcl-bench when
    installed, bench.py when run as tools/bench.py (argparse's prog as well)."""
    return os.path.basename(sys.argv[0]) or "rtcl-tools"


def command_name():
    """Returns how to type the running command again: tools/NAME.py from a checkout,
    else its installed name."""
    name = program_name()
    return f"tools/{name}" if name.endswith(".py") else name


def add_rtcl_option(parser):
    """Adds --rtcl PROGRAM: the rtcl a tool runs (locations.find_rtcl says which
    one it takes without it)."""
    parser.add_argument("--rtcl", metavar="PROGRAM",
                        help="the rtcl program (default: the rtcl installed beside this "
                             "command, else the source tree's ./rtcl, else rtcl on PATH)")


def add_update_committed(parser, default_folder=None):
    """Adds --update-committed: the one way to replace files tracked by git, which
    every writer refuses otherwise (rtcl_tools.files)."""
    where = (f"; the default folder becomes {default_folder}" if default_folder else "")
    parser.add_argument("--update-committed", action="store_true",
                        help="regenerate committed results deliberately: allow replacing "
                             f"files tracked by git, refused otherwise{where}")


class UsageError(Exception):
    """A bad option, or one that is missing (exit status 2)."""


class Parser(argparse.ArgumentParser):
    """argparse that reports a bad option in one line (no usage) with exit status 2."""

    def error(self, message):
        raise UsageError(message)


def check_pair(option, text):
    if not re.fullmatch(r"[1-9][0-9]{0,4}x[1-9][0-9]{0,4}", text):
        raise UsageError(f"{option}: expected WxH with positive integers, got {text!r}")
    return text


def check_positive_int(option, text):
    if not re.fullmatch(r"[1-9][0-9]{0,8}", text):
        raise UsageError(f"{option}: expected a positive integer, got {text!r}")
    return int(text)


def split_list(option, text, convert):
    items = [item.strip() for item in text.split(",")]
    if not text.strip() or any(not item for item in items):
        raise UsageError(f"{option}: expected a comma-separated list, got {text!r}")
    return tuple(convert(option, item) for item in items)


def parse_size(text):
    """Returns (width, height) from "WxH"; an argparse type (its error otherwise)."""
    try:
        w, h = (int(part) for part in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError("expected WxH, e.g. 2000x2000, got %r" % text)
    if not (1 <= w <= 32768 and 1 <= h <= 32768):
        raise argparse.ArgumentTypeError("width and height must be 1 ... 32768, got %r" % text)
    return w, h


def os_error_message(error):
    """Returns an OSError as 'FILE: REASON' (or its own message when it names no file)."""
    if error.filename is not None and error.strerror:
        return f"{error.filename}: {error.strerror}"
    return " ".join(str(error).split())


def report_error(program, message, status=1):
    """Prints 'PROGRAM: error: MESSAGE' on stderr; returns status (the exit status)."""
    print(f"{program}: error: {message}", file=sys.stderr)
    return status
