"""Running the benchmark's configurations: a refusal by rtcl is a skipped row."""

import dataclasses
import pathlib
import shutil
import sys
import tempfile

from .bench_plan import scaled_groups
from .paper import GROUP_KERNELS
from .runner import Progress, RtclFailed, display_command, run_rtcl


class BenchProgress(Progress):
    """experiments' progress lines; a refused run ends its line with the reason."""

    def __init__(self, total, suffix=""):
        super().__init__(total)
        self.suffix = suffix    # appended to every description, e.g. ' at 500x500'

    def start(self, description):
        super().start(description + self.suffix)

    def fail(self, note="failed"):
        pass  # the caller ends the line: 'skipped: REASON' or the error

    def end(self, note):
        print(f" {note}", file=sys.stderr, flush=True)


class SilentProgress(BenchProgress):
    """No progress lines (the probe: its failure is the one line printed)."""

    def start(self, description):
        pass

    def finish(self, kernel_ms):
        pass

    def end(self, note):
        pass


def run_one(settings, progress, kernel, workgroup=None, groups=None, batch=None,
            repeat=None):
    """Runs rtcl once in its own temporary folder; returns (stats, command, reason).

    A refusal by rtcl gives (None, command, rtcl's one-line reason); an rtcl that
    cannot be started or writes no usable statistics raises RtclFailed.
    """
    folder = pathlib.Path(tempfile.mkdtemp(dir=settings.temp_dir))
    own = dataclasses.replace(settings, temp_dir=folder)
    try:
        run = run_rtcl(own, progress, "run", kernel, workgroup, groups, repeat=repeat,
                       batch=batch)
        return run.stats, hide_folders(run.command, settings.temp_dir), None
    except RtclFailed as error:
        if error.returncode is None:
            progress.end("failed")
            raise
        reason = error.reason
        if error.returncode < 0:
            reason = f"rtcl was killed by signal {-error.returncode} ({reason})"
        progress.end(f"skipped: {reason}")
        command = display_command(error.command, folder)
        return None, hide_folders(command, settings.temp_dir), reason
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def hide_folders(command, temp_dir):
    """Returns command with the temporary folders shown as $TMP."""
    return command.replace(str(temp_dir), "$TMP")


def run_sweep(configs, settings, progress):
    """Runs every Config in order, filling in its stats or why it was skipped."""
    defaults = {}     # (kernel, work-group, batch) -> the default-count Config
    measured = {}     # Config.key() -> the Config measured with that geometry
    for config in configs:
        if config.group_scale not in (None, 1.0):
            default = defaults[(config.kernel, config.workgroup, config.batch)]
            if default.stats is None:
                config.skipped = f"the default-groups run was skipped ({default.skipped})"
                progress.start(config.description() + f" ({config.group_scale:g}x groups)")
                progress.end(f"skipped: {config.skipped}")
                continue
            config.groups = scaled_groups(default.stats["groups"], config.group_scale)
        if config.kernel in GROUP_KERNELS and config.groups is not None:
            twin = measured.get(config.key())
            if twin is not None:
                config.skipped = f"same geometry as {twin.description()}, measured there"
                twin.paper = twin.paper or config.paper
                progress.start(config.description())
                progress.end(f"skipped: {config.skipped}")
                continue
        repeat = 1 if config.kernel == "serial" else None
        config.stats, config.command, config.skipped = run_one(
            settings, progress, config.kernel, config.workgroup, config.groups,
            config.batch, repeat)
        if config.group_scale == 1.0:
            defaults[(config.kernel, config.workgroup, config.batch)] = config
        if config.stats is not None:
            measured[config.key()] = config
    if not any(config.stats for config in configs):
        raise RtclFailed("rtcl refused every configuration: "
                         + "; ".join(sorted({c.skipped for c in configs if c.skipped})))


def probe(settings, progress):
    """Runs rtcl on an 8x8 image to learn the device; returns its stats.

    RtclFailed (whatever rtcl's exit status) when it fails: without a device
    nothing else can run.
    """
    common = [option for option in settings.common]
    if "--size" in common:
        at = common.index("--size")
        del common[at:at + 2]
    tiny = dataclasses.replace(settings, common=common + ["--size", "8x8"])
    folder = pathlib.Path(tempfile.mkdtemp(dir=settings.temp_dir))
    try:
        own = dataclasses.replace(tiny, temp_dir=folder)
        return run_rtcl(own, progress, "probe", "naive", repeat=1,
                                    flops=False).stats
    finally:
        shutil.rmtree(folder, ignore_errors=True)
