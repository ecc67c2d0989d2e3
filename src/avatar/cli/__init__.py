"""The ``avatar`` command: one module per group of subcommands, one small function each.

Every ``argparse.Namespace`` stops in this package: the library below takes keyword
arguments. ``AvatarError`` becomes a one-line ``avatar: error: ...`` and exit status 1.
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence

from avatar.cli import clothes, create, dataset, info, mocap, motion, paths
from avatar.errors import AvatarError


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point; returns the exit status (0 ok, 1 Avatar error, 2 usage error)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.DEBUG if args.verbose else logging.INFO,
                        format="%(levelname)s: %(message)s")  # fmt: skip
    if not hasattr(args, "run"):
        parser.print_help()
        return 2
    try:
        return int(args.run(args) or 0)
    except AvatarError as exc:
        print(f"avatar: error: {exc}", file=sys.stderr)
        return 1
    except OSError as exc:  # a write the checks up front could not foresee (disk full, ...)
        print(f"avatar: error: {paths.os_error(exc)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("avatar: interrupted", file=sys.stderr)
        return 130


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="avatar",
        description="Create realistic, rigged, dressed and animated 3D humans "
        "(MakeHuman body model).",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="debug logging")
    sub = parser.add_subparsers(title="commands", metavar="COMMAND")
    create.add_parser(sub)
    info.add_parser(sub)
    motion.add_parsers(sub)
    clothes.add_parsers(sub)
    mocap.add_parsers(sub)
    dataset.add_parsers(sub)
    return parser
