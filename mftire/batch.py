"""Batch commands and client-side writes on top of :mod:`mftire.parallel`.

``mftire fit --each``, ``mftire diagnose --each``: every input file is one task (:func:`run_batch`).  The client
reads each file when its task is sent and sends its bytes (:func:`read_inputs`: the workers need no shared
folder); the worker writes it into a scratch folder (:func:`local_copy`), runs the command's own library
function and writes its outputs there; the files come back as bytes (:class:`mftire.parallel.FilesTask`) and
the client writes them (:func:`write_files`) into a staging folder beside the output folder, published when
every task is done (:func:`mftire.iotools.atomic.staged_folder`): a failed batch writes nothing.  At most twice
as many tasks as workers are in flight (:meth:`mftire.parallel.Executor.stream`), so the client's memory does
not grow with the number of inputs.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

from mftire.errors import MftireInputError
from mftire.parallel import Executor, FilesTask, progress_printer

__all__ = ["InputFile", "local_copy", "read_inputs", "run_batch", "write_files"]


def write_files(folder: str | os.PathLike, files: dict[str, bytes]) -> list[str]:
    """Write ``files`` (relative path -> bytes, from :class:`FilesTask`) into ``folder``, each atomically.
    Returns the paths written."""
    from mftire.iotools.atomic import atomic_path

    out = []
    for rel, data in files.items():
        if os.path.isabs(rel) or ".." in rel.split("/"):
            raise MftireInputError(f"a task returned a file outside its folder: {rel!r}")
        path = os.path.join(os.fspath(folder), *rel.split("/"))
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            fh.write(data)
        out.append(path)
    return out


@dataclass(frozen=True)
class InputFile:
    """One input of a batch: its output name, its file name and its bytes."""

    name: str
    filename: str
    data: bytes


def read_inputs(paths: Sequence[str], names: Sequence[str]) -> Iterator[InputFile]:
    """The inputs of a batch command, each read when its task is sent (the workers need no shared folder)."""
    for path, name in zip(paths, names, strict=True):
        with open(path, "rb") as fh:
            yield InputFile(name, os.path.basename(path), fh.read())


def local_copy(item: InputFile, folder: str) -> str:
    """Write an input's bytes into ``folder`` under its file name (on the worker); its path."""
    path = os.path.join(folder, item.filename)
    with open(path, "wb") as fh:
        fh.write(item.data)
    return path


def run_batch(executor: Executor, task: Callable[[InputFile, str], list[str]], paths: Sequence[str],
              names: Sequence[str], output: str, command: str, what: str) -> list[str]:
    """Run ``task`` (``task(input, folder) -> lines``, writing its outputs into ``folder``) on every input
    file, on ``executor`` with at most twice as many tasks as workers in flight; the client writes every
    task's files into a staging folder beside ``output``, published when every task is done (a failed
    batch writes nothing).  Returns the tasks' lines, in the order of the inputs."""
    from mftire.iotools.atomic import staged_folder

    lines: list[str] = []
    with staged_folder(output) as stage:
        for result, files in executor.stream(FilesTask(task), read_inputs(paths, names), labels=lambda x: x.filename,
                                             progress=progress_printer(f"mftire {command}", what), total=len(paths)):
            write_files(stage, files)
            lines.extend(result)
    return lines
