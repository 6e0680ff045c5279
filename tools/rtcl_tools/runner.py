"""Running rtcl once with --stats (and --flops): the calls every tool makes.

RtclFailed carries the command, its exit status and its stderr, so that callers
read them from the error instead of from its message.
"""

import dataclasses
import json
import pathlib
import shlex
import subprocess
import sys

# What the tables and plots read from every --stats file.
REQUIRED_STATS = ("device", "kernel", "kernel_ms", "workgroup", "groups", "global_size",
                  "width", "height", "max_depth", "scene")


class RtclFailed(Exception):
    """rtcl failed; the message holds the command and rtcl's stderr.

    command is the argument list (None when the failure came before any call),
    returncode rtcl's exit status (None when it did not run or exited 0 but wrote
    no usable statistics), stderr what it printed there.
    """

    def __init__(self, message, command=None, returncode=None, stderr=""):
        super().__init__(message)
        self.command = command
        self.returncode = returncode
        self.stderr = stderr

    @property
    def reason(self):
        """rtcl's own one-line message, else the first line of the message."""
        if self.stderr:
            return rtcl_reason(self.stderr)
        return str(self).splitlines()[0]


def rtcl_reason(stderr):
    """Returns rtcl's one-line message from its stderr, without the 'rtcl: ' prefix."""
    lines = [line.strip() for line in stderr.splitlines() if line.strip()]
    for line in lines:
        if line.startswith("rtcl: "):
            return line[len("rtcl: "):]
    return lines[0] if lines else "no message"


@dataclasses.dataclass
class Run:
    """One rtcl call: what it was for, how it was called, what it reported."""

    role: str               # "paper", "reference", "sweep" or "best"
    kernel: str
    workgroup: str | None
    groups: str | None
    command: str            # the shell line, the temporary folder shown as $TMP
    stats: dict
    flops_path: pathlib.Path | None = None
    batch: int | None = None  # --batch, for the persistent kernel
    histogram: object = None  # histogram.Histogram of its --flops file, if it had one

    def to_json(self):
        item = {"role": self.role, "kernel": self.kernel, "workgroup": self.workgroup,
                "groups": self.groups, "batch": self.batch, "command": self.command,
                "stats": self.stats}
        if self.histogram is not None:
            item["flops_histogram"] = self.histogram.to_json()
        return item


@dataclasses.dataclass
class Settings:
    """The options every rtcl call shares, and how to call it."""

    rtcl: str
    common: list[str]       # device, scene, size and depth options
    repeat: int
    temp_dir: pathlib.Path


class Progress:
    """Prints '[3/14] cyclic -w 8x8 --groups 25x25 ... 12.3 ms' lines on stderr."""

    def __init__(self, total):
        self.total = total
        self.done = 0

    def start(self, description):
        self.done += 1
        print(f"[{self.done}/{self.total}] {description} ...", end="", file=sys.stderr,
              flush=True)

    def finish(self, kernel_ms, note=None):
        print(f" {kernel_ms:.1f} ms" + (f" ({note})" if note else ""), file=sys.stderr,
              flush=True)

    def fail(self, note="failed"):
        print(f" {note}", file=sys.stderr, flush=True)

    def skip(self):
        """A planned run turned out to be a duplicate: count it off."""
        self.total -= 1


def common_options(arguments):
    """Returns the rtcl options shared by every run (device, scene, size, depth)."""
    options = []
    for flag, value in (("-p", arguments.platform), ("-d", arguments.device),
                        ("-s", arguments.scene), ("--size", arguments.size),
                        ("--depth", arguments.depth)):
        if value is not None:
            options += [flag, str(value)]
    return options


# The kernels whose pixels have a schedule map (docs/RENDERING.md).
SCHEDULE_KERNELS = ("serial", "naive", "cyclic", "dynamic", "persistent")


def rtcl_command(settings, name, kernel, workgroup, groups, repeat, batch, flops_path):
    """Returns the argument list of one rtcl call writing NAME.ppm and NAME.json;
    with flops, the schedule map too (NAME.schedule.npy), so that --stats carries
    the modelled SIMD efficiency."""
    command = [settings.rtcl, "-k", kernel, *settings.common,
               "-r", str(repeat or settings.repeat), "-q",
               "-o", str(settings.temp_dir / f"{name}.ppm"), "--encoding", "linear",
               "--stats", str(settings.temp_dir / f"{name}.json")]
    for flag, value in (("-w", workgroup), ("--groups", groups), ("--batch", batch),
                        ("--flops", flops_path)):
        if value:
            command += [flag, str(value)]
    if flops_path and kernel in SCHEDULE_KERNELS:
        command += ["--schedule-map", str(schedule_path(flops_path))]
    return command


def schedule_path(flops_path):
    """The schedule map written beside a flops file."""
    return flops_path.with_suffix(".schedule.npy")


def run_rtcl(settings, progress, role, kernel, workgroup=None, groups=None,
             repeat=None, flops=True, batch=None):
    """Runs rtcl once with --stats (and --flops) and returns the Run."""
    name = "-".join(part for part in (role, kernel, workgroup, groups,
                                      batch and f"b{batch}") if part)
    stats_path = settings.temp_dir / f"{name}.json"
    flops_path = settings.temp_dir / f"{name}.npy" if flops else None
    command = rtcl_command(settings, name, kernel, workgroup, groups, repeat, batch,
                           flops_path)
    progress.start(describe(kernel, workgroup, groups, batch)
                   + (f" ({role})" if role in ("sweep", "best") else ""))
    try:
        result = subprocess.run(command, capture_output=True, text=True)
    except OSError as error:
        progress.fail()
        raise RtclFailed(f"cannot run {settings.rtcl}: {error.strerror}", command) from None
    if result.returncode != 0:
        progress.fail()
        raise RtclFailed(f"rtcl failed (exit {result.returncode}): {shlex.join(command)}\n"
                         f"{result.stderr.rstrip()}", command, result.returncode,
                         result.stderr)
    stats = json.loads(stats_path.read_text(encoding="utf-8"))
    missing = [key for key in REQUIRED_STATS if key not in stats]
    if flops_path and "gflop" not in stats:
        missing.append("gflop")
    if missing:
        progress.fail()
        raise RtclFailed(f"{stats_path.name} lacks {', '.join(missing)}: "
                         f"{shlex.join(command)}", command)
    progress.finish(stats["kernel_ms"])
    return Run(role, kernel, workgroup, groups, display_command(command, settings.temp_dir),
               stats, flops_path, batch)


def describe(kernel, workgroup, groups, batch=None):
    """Returns e.g. 'cyclic -w 8x8 --groups 25x25' or 'persistent ... --batch 2'."""
    text = kernel
    if workgroup:
        text += f" -w {workgroup}"
    if groups:
        text += f" --groups {groups}"
    if batch:
        text += f" --batch {batch}"
    return text


def display_command(command, temp_dir):
    """Returns command as a shell line with the temporary folder shown as $TMP."""
    return shlex.join(command).replace(str(temp_dir), "$TMP")


def parse_pair(text):
    """Returns '25x25' as (25, 25)."""
    first, second = text.lower().split("x")
    return int(first), int(second)


def scaled_groups(groups, scale):
    """Returns '10x10' scaled by 1.5 per dimension as '15x15' (at least 1x1)."""
    columns, rows = parse_pair(groups)
    return f"{max(1, round(columns * scale))}x{max(1, round(rows * scale))}"
