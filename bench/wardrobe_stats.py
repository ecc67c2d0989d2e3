"""Triangles and texture memory of every library item, at the full and game presets.

    python bench/wardrobe_stats.py [--folder DIR ...] [--set gender=1 ...]

For each item (the built-ins, then MakeHuman assets in ``--folder``/$AVATAR_CLOTHES_PATH)
and the body's own parts: triangles (LOD0, and what the game preset's two LODs add),
textures (count and sizes) and texture memory as a GPU holds it uncompressed (RGBA8, 4
bytes a texel, plus a third for the mip chain) at the ``full`` preset (each texture as
sized by the exporter for its part) and the ``game`` one (capped at 1024 px). Prints a
Markdown table for docs/benchmarks.md. Measured on the default body (one fitted outfit per
item), exactly the textures ``avatar create`` would write.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from avatar.cli.assignments import parse_assignments
from avatar.cli.presets import PRESETS
from avatar.clothes import library
from avatar.human import Human
from avatar.io import texture_size
from avatar.part import MeshPart

MIP = 4 / 3  # a full mip chain adds a third


def texture_bytes(part: MeshPart) -> tuple[list[tuple[int, int]], int]:
    """(texture sizes (w, h), bytes as uncompressed RGBA8 with mips) of a part's material."""
    if part.material is None:
        return [], 0
    sizes = [(t.shape[1], t.shape[0]) for t in part.material.textures().values()]
    return sizes, int(sum(w * h * 4 * MIP for w, h in sizes))


def lod_triangles(part: MeshPart, lods: int) -> int:
    """Triangles the LOD levels add (each about half the one before)."""
    from avatar.export import levels_of_detail

    extra, _ = levels_of_detail([part], lods)
    return sum(len(p.mesh.triangles()) for p in extra)


def row(name: str, category: str, part: MeshPart) -> dict:
    full = texture_size.sized([part], PRESETS["full"]["texture_size"])[0]
    game = texture_size.sized([part], PRESETS["game"]["texture_size"])[0]
    full_sizes, full_bytes = texture_bytes(full)
    game_sizes, game_bytes = texture_bytes(game)
    return {
        "name": name, "category": category, "tris": len(part.mesh.triangles()),
        "lod_tris": lod_triangles(part, PRESETS["game"]["lods"]),
        "count": len(full_sizes), "full": full_sizes, "game": game_sizes,
        "full_mb": full_bytes / 2**20, "game_mb": game_bytes / 2**20,
    }  # fmt: skip


def sizes_text(sizes: list[tuple[int, int]]) -> str:
    if not sizes:
        return "-"
    counts: dict[str, int] = {}
    for w, h in sizes:
        key = f"{w}" if w == h else f"{w}x{h}"
        counts[key] = counts.get(key, 0) + 1
    return ", ".join(f"{n}x{k}" if n > 1 else k for k, n in counts.items())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--folder", action="append", default=[], metavar="DIR")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE")
    args = parser.parse_args()
    params = parse_assignments(args.set)
    start = time.perf_counter()
    human = Human(params)
    rows = [row(p.name, "body", p) for p in human.parts()]
    for entry in library.list_garments(folders=args.folder):
        source = entry.name if entry.source == "builtin" else entry.source
        part = library.parts(library.dress(human.body, [source]))[0]
        rows.append(row(entry.name, entry.category, part))
    seconds = time.perf_counter() - start
    print(
        "| item | category | triangles | + game LODs | textures | full: sizes | full MiB "
        "| game: sizes | game MiB |"
    )
    print("|---|---|---:|---:|---:|---|---:|---|---:|")
    for r in rows:
        print(f"| {r['name']} | {r['category']} | {r['tris']:,} | {r['lod_tris']:,} | "
              f"{r['count']} | {sizes_text(r['full'])} | {r['full_mb']:.1f} | "
              f"{sizes_text(r['game'])} | {r['game_mb']:.1f} |")  # fmt: skip
    garments = [r for r in rows if r["category"] != "body"]
    print()
    tris = [r["tris"] for r in garments]
    biggest = max(garments, key=lambda r: r["tris"])["name"]
    full_mb = np.median([r["full_mb"] for r in garments])
    game_mb = np.median([r["game_mb"] for r in garments])
    print(f"{len(garments)} items; median triangles {np.median(tris):,.0f}, max {max(tris):,} "
          f"({biggest}); texture memory per item: full median {full_mb:.1f} MiB, game "
          f"median {game_mb:.1f} MiB")  # fmt: skip
    outfit = ("body", "eyes", "teeth", "tongue", "tshirt", "jeans", "shoes", "hair-short",
              "eyebrows", "eyelashes")  # fmt: skip
    chosen = [r for r in rows if r["name"] in outfit]
    print(
        f"default outfit ({', '.join(outfit[4:])}) with body: "
        f"{sum(r['tris'] for r in chosen):,} triangles, "
        f"{sum(r['full_mb'] for r in chosen):.1f} MiB full, "
        f"{sum(r['game_mb'] for r in chosen):.1f} MiB game "
        f"(textures shared between parts counted once per part); built in {seconds:.0f} s"
    )


if __name__ == "__main__":
    main()
