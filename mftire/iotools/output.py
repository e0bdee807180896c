"""One output policy for every ``mftire`` command.

Every command checks all of its output paths (files, report folders, side files)
with an :class:`OutputPlan` *before* it reads data or computes anything, so a bad
path fails in a second and never after a long fit.  The rules, the same for all
commands:

1. An output must not be one of the command's inputs: the real path (symbolic
   links resolved) and the device and inode (hard links) are compared.  Two
   outputs of one command must differ too.
2. An existing regular file is replaced only with ``--force``; without it the
   command stops with exit code 2 before doing any work.  An existing, non-empty
   output *folder* likewise needs ``--force`` (then files of the same names in it
   are replaced, other files are left alone).  An empty folder is used as is.
3. A character device or a FIFO that the user names (``/dev/null``, a named pipe), and
   ``/dev/stdout``, ``/dev/stderr``, ``/dev/fd/N`` (whatever the shell redirected them
   to), are written *through*: the data is streamed into it and the entry is never
   replaced; ``--force`` is not needed.  Any other non-regular file (a
   folder where a file is expected, a socket, a block device, a symbolic link to a
   missing file) is refused.
4. A symbolic link to a regular file is followed: the file it points to is
   replaced (with ``--force``), the link stays.
5. Missing parent folders are created when the file is written (and removed again
   if the write fails).  A path whose parent cannot be a folder (it is a file) or
   whose nearest existing folder is not writable is refused up front.
6. Every file is written atomically (:mod:`mftire.iotools.atomic`): a temporary
   file beside the target, flushed, then renamed.  On any failure, including
   Ctrl-C, the temporary file is removed and the old file is untouched.
7. A figure's format follows the suffix of its name (``.png``, ``.pdf``, ``.svg``,
   ...); an unknown suffix is refused up front.

``-`` means standard output for the commands that document it.
"""

from __future__ import annotations

import os
import stat
import tempfile
from collections.abc import Iterable

from mftire.errors import MftireInputError
from mftire.iotools.atomic import writes_through

#: Figure formats by file suffix (matplotlib's writers).
FIGURE_FORMATS = {
    ".png": "png", ".pdf": "pdf", ".svg": "svg", ".svgz": "svgz", ".eps": "eps", ".ps": "ps",
    ".jpg": "jpg", ".jpeg": "jpeg", ".tif": "tif", ".tiff": "tiff", ".webp": "webp",
}  # fmt: skip

FORCE_HELP = "replace existing output files (and write into a non-empty output folder); default: refuse"


def figure_format(path: str | os.PathLike) -> str:
    """matplotlib format name for ``path``'s suffix; :class:`MftireInputError` when unknown."""
    suffix = os.path.splitext(os.fspath(path))[1].lower()
    try:
        return FIGURE_FORMATS[suffix]
    except KeyError:
        known = ", ".join(FIGURE_FORMATS)
        what = f"suffix {suffix!r}" if suffix else "no suffix"
        raise MftireInputError(f"{os.fspath(path)}: {what} is not a figure format ({known})") from None


def _identity(path: str) -> tuple[str, tuple[int, int] | None]:
    real = os.path.realpath(path)
    try:
        st = os.stat(path)
    except OSError:
        return real, None
    return real, (st.st_dev, st.st_ino)


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISDIR, "a folder"), (stat.S_ISSOCK, "a socket"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISFIFO, "a FIFO")):
        if test(mode):
            return name
    return "a special file"


def _check_parent(path: str, shown: str) -> None:
    """The nearest existing ancestor of ``path``'s folder must be a writable folder."""
    folder = os.path.dirname(os.path.abspath(path))
    probe = folder
    while not os.path.lexists(probe):
        parent = os.path.dirname(probe)
        if parent == probe:
            break
        probe = parent
    if not os.path.isdir(probe):
        raise MftireInputError(f"{shown}: cannot create folder {folder}: {probe} is not a folder")
    try:
        fd, tmp = tempfile.mkstemp(prefix=".mftire-probe-", dir=probe)
    except OSError as exc:
        raise MftireInputError(f"{shown}: folder {probe} is not writable ({exc.strerror})") from None
    os.close(fd)
    os.unlink(tmp)


class OutputPlan:
    """Check a command's outputs against the policy above, before any work.

    Parameters
    ----------
    inputs : iterable of paths
        Every file the command reads (``-`` and missing files are ignored here).
    force : bool
        The command's ``--force``.
    """

    def __init__(self, inputs: Iterable[str | os.PathLike | None] = (), force: bool = False) -> None:
        self.force = force
        self._inputs: dict[str, tuple[str, tuple[int, int] | None]] = {}
        for p in inputs:
            if p is None or os.fspath(p) in ("", "-"):
                continue
            p = os.fspath(p)
            if os.path.exists(p):
                self._inputs[p] = _identity(p)
        self._outputs: dict[str, str] = {}

    def _not_an_input(self, path: str, shown: str) -> None:
        real, ident = _identity(path)
        for name, (ireal, iident) in self._inputs.items():
            if real == ireal or (ident is not None and ident == iident):
                raise MftireInputError(f"{shown}: output is the input file {name}; choose another output path")
        if real in self._outputs:
            raise MftireInputError(f"{shown}: the same file is also output {self._outputs[real]}")
        self._outputs[real] = shown

    def file(self, path: str | os.PathLike, *, stdout: bool = False, figure: bool = False,
             replace_ok: bool = False) -> str:
        """Check one output file; returns it as ``str``.

        ``stdout``: ``-`` is allowed (standard output).  ``figure``: the suffix must be
        a figure format.  ``replace_ok``: an existing regular file is replaced without
        ``--force`` (used for files inside a folder already accepted by :meth:`folder`).
        """
        path = os.fspath(path)
        if path == "-":
            if stdout:
                return path
            raise MftireInputError("'-' (standard output) is not supported for this output")
        if not path:
            raise MftireInputError("empty output path")
        if figure:
            figure_format(path)
        self._not_an_input(path, path)
        if writes_through(path):
            return path  # a device, FIFO or /dev/stdout: written through (rule 3)
        if os.path.islink(path) and not os.path.exists(path):
            raise MftireInputError(f"{path}: is a symbolic link to a missing file ({os.readlink(path)}); "
                                   "refusing to write through it")
        if os.path.exists(path):
            mode = os.stat(path).st_mode
            if not stat.S_ISREG(mode):
                raise MftireInputError(f"{path}: is {_kind(mode)}; refusing to replace it")
            if not (self.force or replace_ok):
                raise MftireInputError(f"{path}: exists; use --force to replace it")
        _check_parent(os.path.realpath(path), path)
        return path

    def folder(self, path: str | os.PathLike, names: Iterable[str] = ()) -> str:
        """Check an output folder and the files ``names`` the command will write into it."""
        path = os.fspath(path)
        if not path:
            raise MftireInputError("empty output folder path")
        if os.path.lexists(path):
            if not os.path.isdir(path):
                what = "a symbolic link to a missing folder" if not os.path.exists(path) else \
                    _kind(os.stat(path).st_mode) if not os.path.isfile(path) else "a file"
                raise MftireInputError(f"{path}: is {what}, not a folder")
            if os.listdir(path) and not self.force:
                raise MftireInputError(f"{path}: folder is not empty; use --force to write into it "
                                       "(files of the same names are replaced)")
            _check_parent(os.path.join(os.path.realpath(path), "x"), path)
        else:
            _check_parent(os.path.realpath(path), path)
        for name in names:
            self.file(os.path.join(path, name), replace_ok=True)
        return path


__all__ = ["FIGURE_FORMATS", "FORCE_HELP", "OutputPlan", "figure_format"]
