"""What every command does with its files: the spec named on the command line, the output
folders and files checked before any work, and the outputs written all or nothing; a
``UsageError`` (exit status 2, one line) naming the option and the path otherwise."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

__all__ = [
    "UsageError",
    "load_argument",
    "output_folder",
    "output_file",
    "separate_outputs",
    "write_outputs",
]


class UsageError(Exception):
    """Bad command-line usage (exit status 2)."""


def load_argument(text: str, **overrides: Any) -> Any:
    """The spec named on the command line: a file as typed, or a packaged example.

    Reports name the file exactly as typed (``../specs/x.toml`` stays
    relative) and a packaged example by its name, never by the absolute path
    of the machine that ran the command.
    """
    from ..examples import example_path, list_examples
    from ..spec import load_spec

    if not text:
        raise UsageError("SPEC is empty; give a spec file or a packaged example name")
    path = Path(text)
    if not (os.path.lexists(text) or path.suffix) and "\x00" not in text:
        if text in list_examples():
            return load_spec(example_path(text), source=text, **overrides)
        raise UsageError(
            f"{text}: no such file, and no packaged example of that name "
            f"(available: {', '.join(list_examples())})"
        )
    return load_spec(text, **overrides)


def output_folder(option: str, text: str) -> Path:
    """A folder to write into: it exists or can be created, before any work is done."""
    if not text:
        raise UsageError(f"{option}: empty path; give a folder")
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise UsageError(f"{option} {text}: exists and is not a folder")
    ancestor = path
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise UsageError(f"{option} {text}: cannot create a folder there: {ancestor} is a file")
    if not os.access(ancestor, os.W_OK | os.X_OK):
        raise UsageError(f"{option} {text}: cannot write in {ancestor}: permission denied")
    return path


def output_file(option: str, text: str | None) -> Path | None:
    """A file to write (None for no file or '-'), checked before any work is done."""
    if text is None or text == "-":
        return None
    if not text:
        raise UsageError(f"{option}: empty path; give a file path or '-' for stdout")
    path = Path(text)
    if path.is_dir():
        raise UsageError(f"{option} {text}: is a folder, expected a file path")
    parent = path.parent
    if not parent.exists():
        raise UsageError(f"{option} {text}: folder {parent} does not exist")
    if not parent.is_dir():
        raise UsageError(f"{option} {text}: {parent} is not a folder")
    if not path.exists() and not os.access(parent, os.W_OK | os.X_OK):
        raise UsageError(f"{option} {text}: cannot write in {parent}: permission denied")
    return path


def separate_outputs(spec: str, outputs: Sequence[tuple[str, Path | None]]) -> None:
    """UsageError, before any work, where an output is the spec file named on the command line
    (the run would replace it) or two of ``outputs`` are one file (the later would replace the
    earlier).  Each output is (the option as typed, ``--json`` or ``--out FOLDER``, and the
    path it writes)."""
    source = os.path.realpath(spec) if spec and os.path.isfile(spec) else None
    seen: dict[str, str] = {}
    for option, path in outputs:
        if path is None:
            continue
        key = os.path.realpath(path)
        if key == source:
            raise UsageError(
                f"{option}: {path} is the spec file {spec}, which the run would replace; "
                "give another path"
            )
        if key in seen:
            raise UsageError(
                f"{option}: {path} is also the file of {seen[key]}; give each output a path of "
                "its own"
            )
        seen[key] = option


def write_outputs(files: Mapping[Path, str | bytes]) -> None:
    """Write the files all or nothing, creating their folders; UsageError naming the path."""
    from ..base.atomic import write_files

    created: list[Path] = []
    try:
        for parent in dict.fromkeys(path.parent for path in files):  # in order
            missing = []
            while not parent.exists() and parent != parent.parent:
                missing.append(parent)
                parent = parent.parent
            for folder in reversed(missing):
                folder.mkdir()
                created.append(folder)
        write_files(files)
    except BaseException as exc:
        for folder in reversed(created):  # leave no empty folder behind
            try:
                folder.rmdir()
            except OSError:
                pass
        if isinstance(exc, OSError):
            where = exc.filename if exc.filename is not None else ", ".join(map(str, files))
            raise UsageError(f"cannot write {where}: {exc.strerror or exc}") from None
        raise
