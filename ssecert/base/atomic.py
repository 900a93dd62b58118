"""Atomic file writes: a failed or interrupted run leaves no half-written file.

Each file is written to a temporary file in its destination folder, flushed
to disk, then renamed over the destination (``os.replace`` is atomic on one
file system).  ``write_files`` does this for several files at once, all or
nothing: every file is staged before any is renamed, and a failure while
renaming puts back the files already replaced.
"""

from __future__ import annotations

import errno
import os
import stat
import tempfile
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

__all__ = ["atomic_write_text", "write_files"]


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` through a temporary file and a rename.

    The temporary file lives in the destination folder, so the final
    ``os.replace`` is atomic; on any error (or ``KeyboardInterrupt``) it is
    removed and ``path`` is left as it was.  A symbolic link is followed (the
    file it points to is replaced, the link is kept); a device or a named
    pipe (``/dev/stdout``) is written directly, since it cannot be replaced.

    Raises
    ------
    OSError
        With the path in ``filename`` when the file cannot be written.
    """
    return write_files({path: text})[0]


@contextmanager
def _naming(path: Path) -> Iterator[None]:
    """OSErrors name the destination, not a temporary file (or nothing, for a write)."""
    try:
        yield
    except OSError as exc:
        if exc.errno is None:
            raise
        raise OSError(exc.errno, exc.strerror, str(path)) from exc


def _destination(path: Path) -> tuple[Path, bool]:
    """(the path to write, whether it is a stream written in place)."""
    if path.is_symlink():
        path = Path(os.path.realpath(path))
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return path, False
    if stat.S_ISDIR(mode):
        raise IsADirectoryError(errno.EISDIR, "is a folder", str(path))
    return path, not stat.S_ISREG(mode)


def _stage(final: Path, text: str | bytes) -> str:
    """Write ``text`` (or bytes) to a new temporary file beside ``final``; return its name."""
    folder = final.parent if str(final.parent) else Path(".")
    fd, tmp = tempfile.mkstemp(prefix=f".{final.name}.", suffix=".tmp", dir=folder)
    try:
        with _opened(fd, text) as handle:
            handle.write(text)
            handle.flush()
            os.fsync(handle.fileno())
        try:  # keep the mode of a file being replaced, else what open() would give
            mode = stat.S_IMODE(os.stat(final).st_mode)
        except FileNotFoundError:
            umask = os.umask(0)
            os.umask(umask)
            mode = 0o666 & ~umask
        os.chmod(tmp, mode)
    except BaseException:
        _unlink(tmp)
        raise
    return tmp


def _opened(target: Any, content: str | bytes) -> Any:
    """``target`` (a path or a file descriptor) opened for ``content``: UTF-8 text or bytes."""
    if isinstance(content, bytes):
        return open(target, "wb")
    return open(target, "w", encoding="utf-8")


def _unlink(name: str) -> None:
    try:
        os.unlink(name)
    except OSError:
        pass


def write_files(
    files: Mapping[str, str | bytes]
    | Mapping[Path, str | bytes]
    | Mapping[str | Path, str | bytes],
) -> list[Path]:
    """Write several files (text as UTF-8, or bytes), all or nothing.

    Parameters
    ----------
    files : mapping
        Destination path -> text or bytes.

    Returns
    -------
    list of Path
        The destinations, in order.

    Raises
    ------
    OSError
        With the offending path in ``filename``.  No destination is changed
        and no temporary file is left behind.
    """
    targets = [(Path(path), text) for path, text in files.items()]
    staged: list[tuple[str, Path]] = []
    # (copy of the old file, path, existed, renamed yet)
    backups: list[list[Any]] = []
    try:
        streams = []
        for path, text in targets:
            with _naming(path):
                final, stream = _destination(path)
                if stream:
                    streams.append((path, final, text))
                else:
                    staged.append((_stage(final, text), final))
        for path, final, text in streams:
            with _naming(path), _opened(final, text) as handle:
                handle.write(text)
        for tmp, final in staged:
            backup, existed = None, final.exists()
            if existed:
                backup = f"{tmp}.old"
                try:
                    os.link(final, backup)
                except OSError:  # no hard links here: the old file cannot be put back
                    backup = None
            backups.append([backup, final, existed, False])
            os.replace(tmp, final)
            backups[-1][3] = True
    except BaseException:
        for backup, final, existed, renamed in reversed(backups):  # undo the renames done
            if not renamed:
                continue
            try:
                if backup is not None:
                    os.replace(backup, final)
                elif not existed:
                    os.unlink(final)
            except OSError:
                pass
        for tmp, _ in staged:
            _unlink(tmp)
        raise
    finally:
        for backup, *_ in backups:
            if backup is not None:
                _unlink(backup)
    return [path for path, _ in targets]
