"""Writing output files atomically: the one writer every tool uses.

A file is written to a temporary file in the target's folder and renamed over
the target, so that a failure or an interrupt never leaves a partial file and
no temporary file stays behind.  mkstemp creates files 0600: the temporary file
gets the mode a plain open() would give (0666 less the umask) before the rename.
"""

import contextlib
import os
import pathlib
import shutil
import tempfile


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
