"""``avatar info``: parameters, rigs and where the assets are."""

from __future__ import annotations

import argparse

from avatar.body import assets
from avatar.body.model import BodyModel


def add_parser(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "info",
        help="list parameters, rigs and assets",
        description="List parameters (name, range, default), rigs and assets.",
    )
    p.add_argument("--params", action="store_true", help="list every parameter")
    p.add_argument("--search", metavar="TEXT", help="only parameters whose name contains TEXT")
    p.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    model = BodyModel.shared(progress=True)
    print(f"assets: {model.assets.meta['source']}\ncache:  {model.assets.folder}")
    print(f"rigs:   {', '.join(assets.RIG_NAMES)}")
    kinds: dict[str, int] = {}
    for p in model.parameters.values():
        kinds[p.kind] = kinds.get(p.kind, 0) + 1
    print("parameters: " + ", ".join(f"{n} {k}s" for k, n in kinds.items()))
    if args.params or args.search:
        for p in model.parameters.values():
            if args.search and args.search.lower() not in p.name.lower():
                continue
            print(
                f"  {p.name:60s} {p.kind:10s} [{p.minimum:g}, {p.maximum:g}] default {p.default:g}"
            )
    return 0
