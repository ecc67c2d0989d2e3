"""``avatar dataset init|run|validate|sheet``: labelled synthetic humans from one config."""

from __future__ import annotations

import argparse
from pathlib import Path

from avatar.dataset import config as dataset_config
from avatar.dataset import runner, sheet, store
from avatar.errors import AvatarError, ParameterError


def add_parsers(sub: argparse._SubParsersAction) -> None:
    dataset = sub.add_parser("dataset", help="generate labelled synthetic humans",
                             description="Generate a labelled dataset (RGB, depth, normals, "
                             "part and garment segmentation, 2D/3D joints, COCO keypoints, "
                             "cameras) from one seeded, resumable config.")  # fmt: skip
    dsub = dataset.add_subparsers(title="commands", metavar="COMMAND")
    p = dsub.add_parser("init", help="write a documented example config")
    p.add_argument("config", metavar="CONFIG.toml")
    p.add_argument("--force", action="store_true", help="overwrite an existing file")
    p.set_defaults(run=run_init)
    p = dsub.add_parser("run", help="render the samples a folder lacks (resumes)")
    p.add_argument("config", metavar="CONFIG.toml")
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="dataset folder")
    p.add_argument("-n", "--count", type=int, help="number of samples (config: count)")
    p.add_argument("--workers", type=int, default=1, help="worker processes (default 1)")
    p.add_argument("--engine", choices=["local", "ray"], default="local",
                   help="local processes, or Ray tasks (a running cluster or a local one)")
    p.add_argument("--seed", type=int, help="config: seed")
    p.add_argument("--resolution", metavar="WxH", help="config: render.resolution")
    p.add_argument("--samples", type=int, help="config: render.samples (Cycles)")
    p.set_defaults(run=run_run)
    p = dsub.add_parser("validate", help="check a dataset folder")
    p.add_argument("output", metavar="OUT")
    p.set_defaults(run=run_validate)
    p = dsub.add_parser("shards", help="WebDataset tar shards of a dataset folder")
    p.add_argument("output", metavar="OUT")
    p.add_argument("-o", "--dest", required=True, metavar="DIR", help="folder for the shards")
    p.add_argument("--size", type=int, default=1000, help="samples per shard (default 1000)")
    p.set_defaults(run=run_shards)
    p = dsub.add_parser("sheet", help="a contact sheet of some samples (PNG)")
    p.add_argument("output", metavar="OUT")
    p.add_argument("-o", "--png", required=True, metavar="SHEET.png")
    p.add_argument("--ids", default="0:4", metavar="A:B", help="samples A..B-1 (default 0:4)")
    p.set_defaults(run=run_sheet)


def run_init(args: argparse.Namespace) -> int:
    path = Path(args.config)
    if path.exists() and not args.force:
        raise AvatarError(f"{path} exists; use --force to overwrite it")
    store.atomic.write_text(path, dataset_config.EXAMPLE)
    print(f"wrote {path}: edit it, then: avatar dataset run {path} -o OUT")
    return 0


def _resolution(text: str | None) -> tuple[int, int] | None:
    if text is None:
        return None
    w, sep, h = text.lower().partition("x")
    if not sep or not w.isdigit() or not h.isdigit() or not (16 <= int(w) <= 8192
                                                             and 16 <= int(h) <= 8192):
        raise ParameterError(f"--resolution expects WxH within 16..8192, got {text!r}")
    return int(w), int(h)


def run_run(args: argparse.Namespace) -> int:
    for flag, value, low in (("--count", args.count, 1), ("--workers", args.workers, 1),
                             ("--samples", args.samples, 1), ("--seed", args.seed, 0)):
        if value is not None and value < low:
            raise ParameterError(f"{flag} must be at least {low}, got {value}")
    text = Path(args.config).read_text(encoding="utf-8") if Path(args.config).is_file() else None
    config = dataset_config.load(args.config, seed=args.seed, count=args.count,
                                 resolution=_resolution(args.resolution),
                                 samples=args.samples)  # fmt: skip
    report = runner.run(config, args.output, args.workers, args.engine, text, progress=True)
    print(f"{args.output}: {report.rendered} samples rendered in {report.seconds:.1f} s, "
          f"{report.skipped} already there, {len(report.failed)} failed")
    for index, message in sorted(report.failed.items()):
        print(f"  sample {index}: {message}")
    return 1 if report.failed else 0


def run_validate(args: argparse.Namespace) -> int:
    problems = store.validate(Path(args.output))
    for problem in problems:
        print(problem)
    print(f"{args.output}: " + ("ok" if not problems else f"{len(problems)} problems"))
    return 1 if problems else 0


def run_shards(args: argparse.Namespace) -> int:
    if args.size < 1:
        raise ParameterError(f"--size must be at least 1, got {args.size}")
    paths = store.write_shards(Path(args.output), Path(args.dest), args.size)
    print(f"wrote {len(paths)} shards to {args.dest}")
    return 0


def run_sheet(args: argparse.Namespace) -> int:
    a, _, b = args.ids.partition(":")
    try:
        ids = range(int(a), int(b))
    except ValueError:
        raise ParameterError(f"--ids expects A:B, got {args.ids!r}") from None
    print(f"wrote {sheet.sheet(Path(args.output), ids, Path(args.png))}")
    return 0
