"""Command-line interface: ``mftire <command> ...``.

Each sub-package registers its own sub-commands through an ``add_parser(subparsers)``
function; this module only assembles them.  Input errors exit with code 2 and a
one-line message (see :class:`mftire.errors.MftireInputError`).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="mftire", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    from mftire.fe import cli as fe_cli

    fe_cli.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except Exception as exc:  # noqa: BLE001 - user-facing errors are printed on one line
        from mftire.errors import MftireError

        if isinstance(exc, MftireError):
            print(f"mftire {args.command}: error: {exc}", file=sys.stderr)
            return 2
        raise


if __name__ == "__main__":
    sys.exit(main())
