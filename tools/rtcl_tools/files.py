"""Writing output files atomically: the one writer every tool uses.

A file is written to a temporary file in the target's folder and renamed over
the target, so that a failure or an interrupt never leaves a partial file and
no temporary file stays behind.  mkstemp creates files 0600: the temporary file
gets the mode a plain open() would give (0666 less the umask) before the rename.

No writer here replaces or removes a file tracked by git (a `--quick` run once
overwrote committed results): TrackedFileError names the file instead, unless
the block runs under committed_files_allowed(True), which only a tool's
--update-committed option asks for.
"""

import contextlib
import os
import pathlib
import shutil
import subprocess
import tempfile

# Set only inside committed_files_allowed(True): --update-committed.
_committed_allowed = False


class TrackedFileError(OSError):
    """A tool was about to replace or remove a file that git tracks."""

    def __init__(self, path):
        super().__init__(f"{path} is tracked by git: not overwritten (write elsewhere with "
                         "-o/--out DIR, or regenerate committed results deliberately with "
                         "--update-committed, e.g. `make results`)")


@contextlib.contextmanager
def committed_files_allowed(allowed):
    """Lets the writers replace files tracked by git inside the block when allowed
    (a tool's --update-committed); otherwise changes nothing."""
    global _committed_allowed
    before = _committed_allowed
    _committed_allowed = before or bool(allowed)
    try:
        yield
    finally:
        _committed_allowed = before


def _existing_folder(path):
    """Returns the nearest existing folder at or above path's folder."""
    folder = path.parent.absolute()
    while not folder.is_dir() and folder != folder.parent:
        folder = folder.parent
    return folder


def tracked_files(paths):
    """Returns those of paths (files, or folders: every file under them) that a git
    work tree tracks, as paths.  Outside a work tree, or without git, none are."""
    tracked = []
    for path in map(pathlib.Path, paths):
        folder = _existing_folder(path)
        relative = os.path.relpath(path.absolute(), folder)
        try:
            result = subprocess.run(["git", "-C", str(folder), "ls-files", "-z", "--",
                                     relative], capture_output=True, timeout=60)
        except (OSError, subprocess.TimeoutExpired):
            continue
        if result.returncode == 0 and result.stdout:
            names = result.stdout.decode("utf-8", "replace").split("\0")
            tracked += [folder / name for name in names if name]
    return tracked


def check_not_tracked(paths):
    """Raises TrackedFileError for the first of paths (or of the files under a
    folder among them) that git tracks, unless committed_files_allowed."""
    if _committed_allowed:
        return
    tracked = tracked_files(paths)
    if tracked:
        shown = os.path.relpath(tracked[0])
        raise TrackedFileError(tracked[0] if shown.startswith("..") else shown)


def remove(path):
    """Removes the file at path if it exists (TrackedFileError if git tracks it)."""
    path = pathlib.Path(path)
    if path.exists():
        check_not_tracked([path])
        path.unlink()


def current_umask():
    """Returns the process's umask (reading it means setting it: set it back)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _temporary_beside(path):
    """Returns (descriptor, name) of a new temporary file in path's folder.

    OSError names the target, not the temporary file nobody asked for.
    """
    folder = path.parent if str(path.parent) else pathlib.Path(".")
    try:
        return tempfile.mkstemp(dir=folder, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as error:
        raise OSError(error.errno, error.strerror, str(path)) from None


@contextlib.contextmanager
def atomic_output(path, mode="w"):
    """Yields a stream (text "w" or binary "wb") whose contents replace path.

    path is replaced only when the block ends without an exception; otherwise
    the temporary file is removed and path is left as it was.
    """
    path = pathlib.Path(path)
    check_not_tracked([path])
    descriptor, temporary = _temporary_beside(path)
    try:
        encoding = None if "b" in mode else "utf-8"
        newline = None if "b" in mode else ""
        with os.fdopen(descriptor, mode, encoding=encoding, newline=newline) as stream:
            yield stream
        os.chmod(temporary, 0o666 & ~current_umask())
        os.replace(temporary, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(temporary)
        raise


def write_text(path, text):
    """Writes text (UTF-8, newlines as given) to path atomically."""
    with atomic_output(path) as stream:
        stream.write(text)


def copy_file(source, path):
    """Copies file source to path atomically."""
    with atomic_output(path, "wb") as stream, open(source, "rb") as original:
        shutil.copyfileobj(original, stream)


def save_figure(figure, path, file_format, dpi=120):
    """Saves a matplotlib figure to path atomically."""
    with atomic_output(path, "wb") as stream:
        figure.savefig(stream, format=file_format, dpi=dpi)


def write_all(files):
    """Writes {path: text} all or nothing.

    Every file goes to a temporary file first; then each is renamed over its
    target, the previous version kept aside until all are in place, so that a
    failure part-way leaves every target as it was.
    """
    check_not_tracked(files)
    temporaries, kept, placed = [], {}, []
    try:
        for path, text in files.items():
            path.parent.mkdir(parents=True, exist_ok=True)
            descriptor, temporary = _temporary_beside(path)
            temporaries.append(temporary)
            with os.fdopen(descriptor, "w", encoding="utf-8", newline="") as stream:
                stream.write(text)
            os.chmod(temporary, 0o666 & ~current_umask())
        for path, temporary in zip(files, temporaries):
            if path.exists():
                keep = f"{temporary}.previous"
                os.rename(path, keep)
                kept[path] = keep
            os.replace(temporary, path)
            placed.append(path)
    except BaseException:
        for path in placed:
            path.unlink(missing_ok=True)
        for path, keep in kept.items():
            os.rename(keep, path)
        raise
    finally:
        for temporary in temporaries:
            if os.path.exists(temporary):
                os.unlink(temporary)
    for keep in kept.values():
        os.unlink(keep)
