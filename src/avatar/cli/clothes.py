"""``avatar clothes list|bind``: the clothes library and binding a user's garment."""

from __future__ import annotations

import argparse

from avatar.cli.assignments import parse_assignments
from avatar.clothes import binder, library
from avatar.human import Human


def add_parsers(sub: argparse._SubParsersAction) -> None:
    clothes = sub.add_parser("clothes", help="the clothes library",
                             description="List and search the clothes library.")  # fmt: skip
    clothes_sub = clothes.add_subparsers(title="commands", metavar="COMMAND")
    p = clothes_sub.add_parser("list", help="list garments (built-in and user folders)")
    p.add_argument("--search", metavar="TEXT", help="only garments matching every word")
    p.add_argument("--folder", action="append", metavar="DIR",
                   help="also scan this MakeHuman/MPFB asset folder; repeatable")  # fmt: skip
    p.set_defaults(run=run_list)
    p = clothes_sub.add_parser(
        "bind", help="bind a garment OBJ modelled on an Avatar body, so it fits every body",
        description="Bind a garment mesh (OBJ) to the body it was modelled on and save it as "
        "MakeHuman .mhclo + .obj + .mhmat; from then on it fits every body (--wear PATH).",
    )  # fmt: skip
    p.add_argument("garment", metavar="GARMENT.obj")
    p.add_argument("-o", "--output", required=True, metavar="DIR", help="folder to write into")
    body = p.add_mutually_exclusive_group()
    body.add_argument("--set", action="append", metavar="NAME=VALUE",
                      help="the body it was modelled on (as for create); repeatable")  # fmt: skip
    body.add_argument("--mhm", metavar="FILE", help="the body it was modelled on, as a .mhm file")
    p.add_argument("--name", help="garment name (default: the file's stem)")
    p.add_argument("--frame", default="auto", choices=["auto", *binder.FRAMES],
                   help="the OBJ's axes and units (default: whichever fits the body)")  # fmt: skip
    p.add_argument("--tag", action="append", help="library tag; repeatable")
    p.add_argument("--z-depth", type=int, default=50, help="layer: higher goes over lower")
    p.add_argument("--texture", metavar="IMAGE", help="diffuse texture to copy beside it")
    p.set_defaults(run=run_bind)
    p = clothes_sub.add_parser(
        "thumbnails", help="draw library items' pictures (PNG), as the Blender grid shows them",
        description="Draw each item as worn by the default body, from the front (shoes in "
        "profile), in its colours, as a PNG with a transparent background.")  # fmt: skip
    p.add_argument("names", nargs="*", metavar="NAME", help="items (default: every built-in)")
    p.add_argument("--out", metavar="DIR",
                   help="folder to write NAME.png into (default: Avatar's cache, named as the "
                   "Blender extension looks for them)")  # fmt: skip
    p.add_argument("--size", type=int, default=128, help="pixels square (16-1024)")
    p.add_argument("--folder", action="append", metavar="DIR",
                   help="also find items in this MakeHuman/MPFB asset folder; repeatable")
    p.add_argument("--missing", action="store_true",
                   help="only the items whose cached picture is missing (without --out)")
    p.set_defaults(run=run_thumbnails)


def run_list(args: argparse.Namespace) -> int:
    """Print the library: name, category, licence, tags."""
    entries = library.list_garments(args.search, args.folder or ())
    width = max((len(e.name) for e in entries), default=4)
    for e in entries:
        print(f"{e.name:<{width}}  {e.category:<9}  {e.licence:<6}  {', '.join(e.tags)}")
    if not entries:
        print("no garments match")
    return 0


def run_bind(args: argparse.Namespace) -> int:
    """Bind the OBJ to the body it was modelled on (``binder.bind_obj``)."""
    human = Human.from_mhm(args.mhm) if args.mhm else Human(parse_assignments(args.set or []))
    path = binder.bind_obj(args.garment, human.body, args.output, name=args.name,
                           frame=args.frame, tags=tuple(args.tag or ()), z_depth=args.z_depth,
                           texture=args.texture)  # fmt: skip
    print(f"wrote {path}: wear it on any body with --wear {path}")
    return 0


def run_thumbnails(args: argparse.Namespace) -> int:
    """Write one picture per item (``clothes.thumbnail``); every name is checked first, so
    a bad one writes nothing."""
    from pathlib import Path

    from avatar.clothes import thumbnail
    from avatar.errors import ParameterError

    if not 16 <= args.size <= 1024:
        raise ParameterError(f"--size must be 16-1024 pixels, got {args.size}")
    names = args.names or [e.name for e in library.builtin_entries()]
    # unknown: ParameterError naming close matches; a user item's picture is of its file
    sources = [library.find_garment(name, args.folder or ()) for name in names]
    if args.missing and not args.out:
        for written in thumbnail.draw_missing(sources, args.size):
            print(f"wrote {written}", flush=True)
        return 0
    for name, source in zip(names, sources, strict=True):
        path = Path(args.out) / f"{Path(name).stem}.png" if args.out else None
        written = thumbnail.write_picture(source, args.size, path)
        print(f"wrote {written}", flush=True)
    return 0
