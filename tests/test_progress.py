"""One progress reporter (issue 25): stderr only, quiet when stderr is not a terminal or with --quiet."""

from __future__ import annotations

import io

import pytest

from mftire.cli import build_parser
from mftire.progress import Progress, reporter


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_quiet_unless_a_terminal():
    plain, tty = io.StringIO(), _Tty()
    Progress("mftire fit", stream=plain)("stage 1")
    Progress("mftire fit", stream=tty)("stage 1")
    assert plain.getvalue() == ""
    assert tty.getvalue().endswith("] mftire fit: stage 1\n") and tty.getvalue().startswith("[")
    forced = io.StringIO()
    Progress("mftire fit", True, stream=forced)("stage 1")
    assert "mftire fit: stage 1" in forced.getvalue()
    off = _Tty()
    Progress("mftire fit", False, stream=off)("stage 1")
    assert off.getvalue() == ""


def test_steps_updates_and_sinks():
    tty = _Tty()
    p = Progress("mftire demo", stream=tty, total=3)
    p.step("one")
    p.update("chunk 1/2")
    p.update("chunk 2/2")
    p.step("two")
    p.done()
    lines = tty.getvalue().split("\n")
    assert lines[0].startswith("[1/3 ") and lines[0].endswith("mftire demo: one")
    assert "\r" in lines[1] and "chunk 2/2" in lines[1] and "[2/3 " in lines[1]  # in place, then the next step
    got: list[str] = []
    r = reporter(got.append, "mftire bands")
    r("replicate 1")
    r.update("replicate 2")
    assert got == ["replicate 1", "replicate 2"]
    assert reporter(r, "other") is r  # a step inside a longer command reports through the command's reporter


def test_default_stream_is_stderr_at_creation(capsys):
    Progress("mftire fe", True)("x")
    out = capsys.readouterr()
    assert out.out == "" and "mftire fe: x" in out.err


@pytest.mark.parametrize("argv", [["demo", "--quick", "--quiet"], ["fit", "d.csv", "--template", "t.tir", "--output",
                                  "o.tir", "--quiet"], ["diagnose", "d.csv", "--tir", "t.tir", "--output", "o", "-q"],
                                  ["fe", "campaign", "--output", "o", "--quiet"]])
def test_long_commands_take_quiet(argv):
    from mftire.cli_options import progress_of

    args = build_parser().parse_args(argv)
    assert args.quiet and progress_of(args) is False
    args = build_parser().parse_args([a for a in argv if a not in ("--quiet", "-q")])
    assert progress_of(args) is None
