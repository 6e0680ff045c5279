"""Writing output files atomically: the one writer every tool uses.

A file is written to a temporary file in the target's folder and renamed over
the target, so that a failure or an interrupt never leaves a partial file and
no temporary file stays behind.  mkstemp creates files 0600: the temporary file
gets the mode a plain open() would give (0666 less the umask) before the rename.

No writer here replaces or removes a file tracked by git (a `--quick` run once
overwrote committed results): TrackedFileError names the file instead, unless
the block runs under committed_files_allowed(True), which only a tool's
--update-committed option asks for.

Nor does any writer replace a file the tool reads (`rtcl-povray -s x.json -o
x.json` once replaced the scene): a tool names what it reads with reading(PATHS)
before it checks or writes anything, and an output that names one of them, by its
path, through a symbolic link or as another name of the same inode (a hard link),
is InputFileError, as rtcl refuses an output over its scene.  check_outputs(PATHS)
applies both rules (and refuses a folder where a file is to be written) before a
tool's work, so that what would fail at the end fails at once.

Inputs are opened with open_input(), which refuses what is not a regular file
(a folder, a FIFO, a device) with one line instead of blocking on it.
"""

import contextlib
import errno
import os
import pathlib
import shutil
import stat
import subprocess
import tempfile

# Set only inside committed_files_allowed(True): --update-committed.
_committed_allowed = False
# What the running tool reads: {(st_dev, st_ino): the path as given} (reading()).
_inputs = {}


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


class InputFileError(OSError):
    """A tool was about to replace a file that it reads."""

    def __init__(self, output, source):
        how = "" if os.path.abspath(output) == os.path.abspath(source) else \
            f" (the same file as {source}, by a link or another name)"
        super().__init__(f"{output} is an input of this run{how}: not overwritten (name "
                         "another output file)")


def reading(paths):
    """Registers paths (files that exist; others are skipped) as what the running
    tool reads: no writer here replaces them, by any name (InputFileError)."""
    for path in paths:
        if path is None:
            continue
        try:
            info = os.stat(path)
        except (OSError, ValueError):
            continue
        _inputs.setdefault((info.st_dev, info.st_ino), str(path))


@contextlib.contextmanager
def inputs_forgotten():
    """Forgets the registered inputs when the block ends (tests that call several
    tools' main() in one process)."""
    before = dict(_inputs)
    try:
        yield
    finally:
        _inputs.clear()
        _inputs.update(before)


def check_not_input(paths):
    """Raises InputFileError for the first of paths that names a file the tool reads:
    by its path, a symbolic link to it or another name of its inode."""
    for path in paths:
        try:
            info = os.stat(path)
        except (OSError, ValueError):
            continue
        source = _inputs.get((info.st_dev, info.st_ino))
        if source is not None:
            raise InputFileError(path, source)


def check_outputs(paths, folders_made=False):
    """Refuses, before any work, to write the files at paths: a file tracked by git
    (TrackedFileError), a file the tool reads (InputFileError), a folder where a file
    goes, a missing folder (unless folders_made: the writer makes it, as write_all
    does) or a file where a folder would be (OSError, naming the path)."""
    paths = [pathlib.Path(path) for path in paths]
    check_not_input(paths)
    for path in paths:
        if path.is_dir():
            raise IsADirectoryError(errno.EISDIR, "is a folder, not a file", str(path))
        if not folders_made and not path.parent.exists():
            raise FileNotFoundError(errno.ENOENT, f"{os.strerror(errno.ENOENT)} (no folder "
                                    f"{path.parent})", str(path))
        _check_folder_can_hold(path.parent, folders_made)
    check_not_tracked(paths)


def check_output_folder(folder, names):
    """check_outputs for the files names in folder, the folder made later if missing;
    a folder given as the name of an existing file is refused."""
    folder = pathlib.Path(folder)
    if folder.exists() and not folder.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, "is a file, not a folder: name the folder "
                                 "to write into", str(folder))
    _check_folder_can_hold(folder, True)
    check_outputs([folder / name for name in names], True)


def _check_folder_can_hold(folder, made=False):
    """Raises OSError when files cannot be written into folder: it is missing
    (unless made: then the nearest existing folder above it must take it), a file
    stands at it or above it, or the folder is not writable."""
    folder = folder if str(folder) else pathlib.Path(".")
    existing = folder
    while made and not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.exists():
        raise FileNotFoundError(errno.ENOENT, "no such folder", str(existing))
    if not existing.is_dir():
        raise NotADirectoryError(errno.ENOTDIR, "is a file, not a folder", str(existing))
    if not os.access(existing, os.W_OK | os.X_OK):
        raise PermissionError(errno.EACCES, "folder not writable", str(existing))


FILE_KINDS = ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
              (stat.S_ISSOCK, "a socket"), (stat.S_ISCHR, "a character device"),
              (stat.S_ISBLK, "a block device"))


def not_regular_reason(mode):
    """Returns what a file of mode is when it is not a regular file, else None."""
    if stat.S_ISREG(mode):
        return None
    return next((name for test, name in FILE_KINDS if test(mode)), "not a regular file")


class NotRegularFileError(OSError):
    """An input that is not a regular file; the message names it and what it is."""


def open_input(path, mode="rb"):
    """Opens the regular file at path for reading ("rb", or "r" for UTF-8 text).

    A folder, FIFO, socket or device is NotRegularFileError ("PATH: is a FIFO (named
    pipe), not a regular file"), found without blocking: the file is opened with
    O_NONBLOCK (a FIFO opens at once) and its kind read from the open descriptor.
    A missing or unreadable file is the OSError of the open, naming path."""
    flags = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0)
    try:
        descriptor = os.open(path, flags)
    except IsADirectoryError:
        raise NotRegularFileError(errno.EISDIR, "is a folder, not a regular file",
                                  str(path)) from None
    try:
        kind = not_regular_reason(os.fstat(descriptor).st_mode)
        if kind is not None:
            raise NotRegularFileError(errno.EINVAL, f"is {kind}, not a regular file",
                                      str(path))
        os.set_blocking(descriptor, True)
        if "b" in mode:
            return os.fdopen(descriptor, "rb")
        return os.fdopen(descriptor, "r", encoding="utf-8")
    except BaseException:
        os.close(descriptor)
        raise


def check_input_files(paths):
    """Raises OSError (naming the file and what is wrong) for the first of paths that
    is missing, unreadable or not a regular file: checked before a tool's work."""
    for path in paths:
        if path is not None:
            open_input(path).close()


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
    """Removes the file at path if it exists (TrackedFileError if git tracks it,
    InputFileError if the tool reads it)."""
    path = pathlib.Path(path)
    if path.exists():
        check_not_input([path])
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
    check_not_input([path])
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
    check_not_input(files)
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
