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
8. While a command runs (:func:`command_scope`, entered by :func:`mftire.cli.main`), every
   write goes through here (:func:`final_rename`, called by :mod:`mftire.iotools.atomic`):
   a file that is neither a checked output nor inside a checked output folder is refused,
   and without ``--force`` the final rename does not replace a file that appeared while
   the command ran (another run writing the same output): a no-replace rename
   (``renameat2(RENAME_NOREPLACE)``, else a hard link then unlink).  A file this run
   wrote itself may be rewritten.
9. A name taken from data (a column, a run or a file label) that becomes part of a file
   name is reduced to a safe slug by :func:`safe_name` (letters, digits, ``._-``; never a
   path, never hidden), unique within the command.

``-`` means standard output for the commands that document it.
"""

from __future__ import annotations

import contextlib
import contextvars
import ctypes
import ctypes.util
import errno
import hashlib
import os
import re
import stat
import tempfile
from collections.abc import Iterable, Iterator

from mftire.errors import MftireInputError

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


class _Scope:
    """The outputs one command checked (:class:`OutputPlan`), while it runs."""

    def __init__(self) -> None:
        self.files: set[str] = set()  # real paths of checked output files
        self.folders: set[str] = set()  # real paths of checked output folders
        self.force = False
        self.written: set[str] = set()  # real paths this run wrote (may be rewritten)
        self.slugs: dict[str, str] = {}  # safe_name: label -> name, and back
        self.inputs: dict[str, str] = {}  # real paths of the inputs -> as given


_SCOPE: contextvars.ContextVar[_Scope | None] = contextvars.ContextVar("mftire_output_scope", default=None)


@contextlib.contextmanager
def command_scope() -> Iterator[None]:
    """The output scope of one command (:func:`mftire.cli.main`): the plans made inside register their
    outputs, and :func:`final_rename` holds every write to them (rule 8).  Outside a scope (the
    library) a write replaces its target as :func:`os.replace`."""
    token = _SCOPE.set(_Scope())
    try:
        yield
    finally:
        _SCOPE.reset(token)


def _real(path: str) -> str:
    return os.path.realpath(os.path.abspath(path))


def _inside(path: str, folders: Iterable[str]) -> bool:
    for f in folders:
        with contextlib.suppress(ValueError):
            if os.path.commonpath([path, f]) == f:
                return True
    return False


_RENAME_NOREPLACE = 1
_renameat2 = None


def _libc_renameat2():
    global _renameat2
    if _renameat2 is None:
        fn = False
        with contextlib.suppress(OSError, AttributeError, TypeError):
            libc = ctypes.CDLL(ctypes.util.find_library("c") or None, use_errno=True)
            fn = libc.renameat2
            fn.argtypes = (ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p, ctypes.c_uint)
            fn.restype = ctypes.c_int
        _renameat2 = fn
    return _renameat2 or None


def rename_noreplace(src: str, dst: str) -> None:
    """Rename ``src`` to ``dst`` unless ``dst`` exists (:class:`FileExistsError`), atomically:
    ``renameat2(RENAME_NOREPLACE)`` (Linux), else a hard link then unlink of ``src``; on a file
    system with neither, a check then :func:`os.replace` (a short race window remains there)."""
    fn = _libc_renameat2()
    if fn is not None:
        at_fdcwd = -100
        rc = fn(at_fdcwd, os.fsencode(src), at_fdcwd, os.fsencode(dst), _RENAME_NOREPLACE)
        if rc == 0:
            return
        err = ctypes.get_errno()
        if err == errno.EEXIST:
            raise FileExistsError(err, os.strerror(err), dst)
        if err not in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
            raise OSError(err, os.strerror(err), dst)
    try:
        os.link(src, dst)
    except FileExistsError:
        raise
    except OSError:  # no hard links here (FAT, some network file systems)
        if os.path.lexists(dst):
            raise FileExistsError(errno.EEXIST, os.strerror(errno.EEXIST), dst) from None
        os.replace(src, dst)
        return
    os.unlink(src)


def final_rename(tmp: str, path: str) -> None:
    """Move the finished temporary file ``tmp`` onto ``path`` under the running command's policy
    (rule 8); outside a command, :func:`os.replace`."""
    scope = _SCOPE.get()
    if scope is None:
        os.replace(tmp, path)
        return
    real = _real(path)
    if real in scope.inputs:
        raise MftireInputError(f"{path}: is the input file {scope.inputs[real]}; refusing to replace it")
    if real not in scope.files and not _inside(real, scope.folders):
        where = ", ".join(sorted(scope.folders | scope.files)) or "none"
        raise MftireInputError(f"{path}: not an output of this command (its outputs: {where}); refusing to write it")
    if scope.force or real in scope.written:
        os.replace(tmp, path)
    else:
        try:
            rename_noreplace(tmp, path)
        except FileExistsError:
            raise MftireInputError(f"{path}: appeared while this command ran (another run?); not replaced, "
                                   "use --force to replace it") from None
    scope.written.add(real)


def allow_staging(folder: str | os.PathLike) -> None:
    """Let the running command write into ``folder``, a private staging folder of its own
    (:func:`mftire.iotools.atomic.staged_folder`) whose files are moved onto the checked outputs at the end;
    outside a command, nothing to do."""
    scope = _SCOPE.get()
    if scope is not None:
        scope.folders.add(_real(os.fspath(folder)))


_SLUG_BAD = re.compile(r"[^A-Za-z0-9._-]+")


def safe_name(label: object, max_length: int = 60) -> str:
    """A file-name part from a label taken from data (a column, a run, a file label): never a path.

    Letters, digits, ``.``, ``_`` and ``-`` are kept, any other run of characters (``/``, ``..``,
    spaces, control characters, non-ASCII) becomes ``_``; leading dots and dashes are dropped (no
    hidden file, no option), the length is bounded.  A label that had to be changed gets a short
    hash of the original, so two labels never share a name; while a command runs, a name is also
    unique among the labels it has given (``Fz`` and ``fz`` on a case-insensitive disk: ``fz_2``).
    """
    text = str(label)
    slug = re.sub(r"\.{2,}", "_", _SLUG_BAD.sub("_", text)).lstrip("._-")
    slug = re.sub(r"_+", "_", slug).strip("_")[:max_length].rstrip(".") or "x"
    if slug != text:
        slug = f"{slug}_{hashlib.sha1(text.encode('utf-8', 'surrogatepass')).hexdigest()[:6]}"
    scope = _SCOPE.get()
    if scope is None:
        return slug
    key = "label:" + text
    if key in scope.slugs:
        return scope.slugs[key]
    base, n = slug, 1
    while "name:" + slug.lower() in scope.slugs:
        n += 1
        slug = f"{base}_{n}"
    scope.slugs[key] = slug
    scope.slugs["name:" + slug.lower()] = text
    return slug


def writes_through(path: str | os.PathLike) -> bool:
    """True when ``path`` is written *through* instead of replaced: it is (or links to) a
    character device or a FIFO, or it names a descriptor of this process (``/dev/stdout``,
    ``/dev/fd/N``, ``/proc/self/fd/N``; even when the shell redirected it to a regular file,
    which must then be filled, not swapped for a new file the shell does not hold)."""
    name = os.path.abspath(os.fspath(path))
    if name in ("/dev/stdout", "/dev/stderr") or name.startswith(("/dev/fd/", "/proc/self/fd/")):
        return os.path.exists(name)
    try:
        mode = os.stat(name).st_mode
    except OSError:
        return False
    return stat.S_ISCHR(mode) or stat.S_ISFIFO(mode)


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
        scope = _SCOPE.get()
        if scope is not None:
            scope.inputs.update({ident[0]: name for name, ident in self._inputs.items()})
        self._outputs: dict[str, str] = {}
        self._scope = _SCOPE.get()
        if self._scope is not None:
            self._scope.force = self._scope.force or force

    def _not_an_input(self, path: str, shown: str) -> None:
        real, ident = _identity(path)
        for name, (ireal, iident) in self._inputs.items():
            if real == ireal or (ident is not None and ident == iident):
                raise MftireInputError(f"{shown}: output is the input file {name}; choose another output path")
        if real in self._outputs:
            raise MftireInputError(f"{shown.rstrip(os.sep)}: the same file is also output {self._outputs[real]}")
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
        if path.endswith(("/", os.sep)) or os.path.basename(path) in (".", ".."):
            raise MftireInputError(f"{path}: names a folder; this output is a file (give a file name)")
        if figure:
            figure_format(path)
        self._not_an_input(path, path)
        if writes_through(path):
            return path  # a device, FIFO or /dev/stdout: written through (rule 3)
        if self._scope is not None:
            self._scope.files.add(_real(path))
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
        shown = path.rstrip("/" + os.sep) or path
        self._not_an_input(path, shown + os.sep)  # an input or another output is not a folder to write into
        if self._scope is not None:
            self._scope.folders.add(_real(path))
        for name in names:
            self.file(os.path.join(path, name), replace_ok=True)
        return path


__all__ = ["FIGURE_FORMATS", "FORCE_HELP", "OutputPlan", "allow_staging", "command_scope", "figure_format",
           "final_rename", "rename_noreplace", "safe_name", "writes_through"]
