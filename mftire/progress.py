"""One progress reporter for the long steps (FE campaign, fit, bands, diagnosis, demo).

Progress goes to stderr, never stdout (stdout carries results: tables, summaries), and is
quiet unless stderr is a terminal, so that piped and logged runs and the tests stay clean.
``--quiet`` on the long commands turns it off on a terminal too; ``progress=True`` in
the API turns it on anywhere.

A line reads ``[  12.3 s] mftire fit: stage 2 lateral [Fy]: rms ...`` (elapsed time
since the reporter started, the command, the message); :meth:`Progress.step` numbers the
steps (``[3/9  12.3 s] ...``) and :meth:`Progress.update` rewrites one line in place
(chunks of a campaign).  No dependency: a few lines of our own do what tqdm would.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import TextIO

__all__ = ["Progress", "reporter"]


class Progress:
    """Progress lines of one long command on stderr.

    Parameters
    ----------
    name : str
        The command or step (``"mftire fit"``), printed before every message.
    enabled : bool or None
        None: on when the stream is a terminal; True/False: on/off.
    total : int, optional
        Number of steps, for :meth:`step` (``[i/total ...]``).
    stream : text stream, optional
        Default ``sys.stderr`` (looked up when the reporter is made, so captured streams work).
    sink : callable, optional
        Called with each message instead of printing (the API's ``progress=callable``).
    """

    def __init__(self, name: str = "mftire", enabled: bool | None = None, *, total: int | None = None,
                 stream: TextIO | None = None, sink: Callable[[str], None] | None = None) -> None:
        self.name = name
        self.stream = stream if stream is not None else sys.stderr
        self.sink = sink
        if enabled is None:
            enabled = sink is not None or _is_terminal(self.stream)
        self.enabled = bool(enabled)
        self.total = total
        self.i = 0
        self.t0 = time.perf_counter()
        self._open = False  # a line written by update() waits for its end

    def elapsed(self) -> float:
        """Seconds since the reporter started [s]."""
        return time.perf_counter() - self.t0

    def _write(self, text: str, end: str = "\n") -> None:
        if self._open and end == "\n":
            text = "\r" + text + "\x1b[K"
        print(text, end=end, file=self.stream, flush=True)
        self._open = end != "\n"

    def _passed_on(self, msg: str) -> bool:
        """Whether nothing is left to write here: reporting is off, or the sink took the message."""
        if self.enabled and self.sink is not None:
            self.sink(msg)
        return not self.enabled or self.sink is not None

    def __call__(self, msg: str) -> None:
        """One progress line."""
        if not self._passed_on(msg):
            self._write(f"[{self.elapsed():6.1f} s] {self.name}: {msg}")

    def step(self, msg: str) -> None:
        """The next numbered step (``[i/total t s] name: msg``)."""
        self.i += 1
        if not self._passed_on(msg):
            of = f"/{self.total}" if self.total else ""
            self._write(f"[{self.i}{of} {self.elapsed():5.1f} s] {self.name}: {msg}")

    def update(self, msg: str) -> None:
        """Rewrite the current line in place (on a terminal; a plain line elsewhere)."""
        if self._passed_on(msg):
            return
        if _is_terminal(self.stream):
            print(f"\r[{self.elapsed():6.1f} s] {self.name}: {msg}\x1b[K", end="", file=self.stream, flush=True)
            self._open = True
        else:
            self._write(f"[{self.elapsed():6.1f} s] {self.name}: {msg}")

    def done(self) -> None:
        """End a line left open by :meth:`update`."""
        if self._open:
            print(file=self.stream, flush=True)
            self._open = False


def reporter(progress: bool | Callable[[str], None] | Progress | None, name: str,
             total: int | None = None) -> Progress:
    """A :class:`Progress` from an API's ``progress=`` argument.

    ``progress`` is None (on when stderr is a terminal), a bool, a callable that takes
    every message, or a :class:`Progress`.
    A :class:`Progress` passed in is returned as it is (a step inside a longer command
    reports through the command's reporter); a callable receives every message.
    """
    if isinstance(progress, Progress):
        return progress
    if callable(progress):
        return Progress(name, True, total=total, sink=progress)
    return Progress(name, progress, total=total)


def _is_terminal(stream: TextIO) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # closed or replaced streams
        return False
