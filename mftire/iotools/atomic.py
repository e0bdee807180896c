"""Atomic file writes: write to a temporary file beside the target, then rename.

The rename is :func:`mftire.iotools.output.final_rename`: while a command runs it refuses
files that are not the command's outputs and, without ``--force``, does not replace a file
that appeared meanwhile; in library use it is :func:`os.replace`.

A failed write leaves the target untouched, and readers never see a half-written
file (and no temporary file is left behind).  The new file keeps the permissions of the file it replaces (0644 for a new
file).
"""

from __future__ import annotations

import contextlib
import errno
import os
import shutil
import stat
import sys
import tempfile
from collections.abc import Iterator

from mftire.iotools import output as _output
from mftire.iotools.output import writes_through


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[str]:
    """Yield a temporary path in the target's directory; ``os.replace`` it on success.

    If the body raises, the temporary file is removed and ``path`` is untouched.

    The target is resolved first: a symbolic link to a file is followed (the file is
    replaced, the link stays); a character device or FIFO (``/dev/null``, a named
    pipe) is written *through* (the data is copied into it, the entry is kept); any
    other non-regular file is refused with :class:`OSError`.  Missing parent
    folders are created, and removed again if the body fails.
    """
    if writes_through(path):
        yield from _through(os.fspath(path))
        return
    path = os.path.realpath(os.fspath(path)) if os.path.islink(path) else os.fspath(path)
    try:
        st = os.stat(path)
    except OSError:
        st = None
    if st is not None and not stat.S_ISREG(st.st_mode):
        raise IsADirectoryError(errno.EISDIR, "not a regular file; refusing to replace it", path)
    mode = st.st_mode & 0o777 if st is not None else 0o644
    directory = os.path.dirname(os.path.abspath(path))
    created = _makedirs(directory)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{os.path.basename(path)}.", suffix=".tmp", dir=directory)
    except BaseException:
        _removedirs(created)
        raise
    os.close(fd)
    try:
        yield tmp
        os.chmod(tmp, mode)
        _output.final_rename(tmp, path)  # the running command's policy (output.py, rule 8)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        _removedirs(created)
        raise


def _descriptor(path: str) -> int | None:
    """The descriptor number ``/dev/stdout``, ``/dev/stderr``, ``/dev/fd/N`` or ``/proc/self/fd/N`` names."""
    name = os.path.abspath(path)
    fixed = {"/dev/stdout": 1, "/dev/stderr": 2}
    if name in fixed:
        return fixed[name]
    for prefix in ("/dev/fd/", "/proc/self/fd/"):
        if name.startswith(prefix) and name[len(prefix):].isdigit():
            return int(name[len(prefix):])
    return None


def _through(path: str) -> Iterator[str]:
    """Write into a character device, a FIFO or an open descriptor: a temporary file
    elsewhere, then copied in.  A descriptor (``/dev/stdout``) is written as it is open,
    not reopened, so a shell's ``>>`` appends and ``>`` is not truncated twice."""
    fd, tmp = tempfile.mkstemp(prefix="mftire-", suffix=".tmp")
    os.close(fd)
    try:
        yield tmp
        number = _descriptor(path)
        if number is not None:
            with contextlib.suppress(AttributeError, ValueError, OSError):
                sys.stdout.flush()  # what was printed before comes first
            dst = open(os.dup(number), "wb")  # noqa: SIM115 - closed below
        else:
            dst = open(path, "wb")  # noqa: SIM115 - closed below
        with open(tmp, "rb") as src, dst:
            shutil.copyfileobj(src, dst)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)


def _makedirs(directory: str) -> list[str]:
    """Create ``directory`` and missing parents; return the created ones, deepest first."""
    created = []
    d = directory
    while not os.path.isdir(d):
        created.append(d)
        parent = os.path.dirname(d)
        if parent == d:
            break
        d = parent
    os.makedirs(directory, exist_ok=True)
    return created


def _removedirs(created: list[str]) -> None:
    for d in created:
        with contextlib.suppress(OSError):
            os.rmdir(d)


def write_text_atomic(path: str | os.PathLike, text: str, newline: str | None = "") -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically, flushed to disk before the rename.

    ``newline`` is passed to :func:`open` (``""``: no translation).
    """
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8", newline=newline) as fh:
        fh.write(text)
        fh.flush()
        os.fsync(fh.fileno())


@contextlib.contextmanager
def staged_folder(folder: str | os.PathLike) -> Iterator[str]:
    """Yield a hidden staging folder beside ``folder``; on success move every file written into it to the same
    place in ``folder`` (each with one ``os.replace``: other files of ``folder`` are left alone), on failure
    (including Ctrl-C) remove it: a run that fails writes nothing into ``folder``.  Missing parents of
    ``folder`` are created, and removed again on failure."""
    folder = os.fspath(folder)
    parent = os.path.dirname(os.path.abspath(folder))
    created = _makedirs(parent)
    try:
        stage = tempfile.mkdtemp(prefix=f".{os.path.basename(os.path.abspath(folder))}.partial-", dir=parent)
    except BaseException:
        _removedirs(created)
        raise
    try:
        _output.allow_staging(stage)  # the running command may write into its own staging folder
        yield stage
        os.makedirs(folder, exist_ok=True)
        for root, _dirs, names in os.walk(stage):
            target = os.path.join(folder, os.path.relpath(root, stage))
            os.makedirs(target, exist_ok=True)
            for name in names:
                src, dst = os.path.join(root, name), os.path.join(target, name)
                if os.path.islink(dst) or writes_through(dst):  # a link is followed, a device written through
                    with atomic_path(dst) as tmp:
                        shutil.copyfile(src, tmp)
                else:
                    os.replace(src, dst)
    except BaseException:
        _removedirs(created)
        raise
    finally:
        shutil.rmtree(stage, ignore_errors=True)
