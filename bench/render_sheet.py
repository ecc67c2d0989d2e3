"""The "Must show" render sheet of issue 14: eight bodies dressed in Avatar's built-ins, next
to the same bodies in MakeHuman's CC0 assets, front, back and head-and-shoulders, at rest and
mid-stride (docs/images/sheet_<view>_<pose>.png).

    python bench/render_sheet.py [--samples 16] [--width 1200] [--out docs/images]
                                 [--views front,back,closeup] [--poses rest,walk]
                                 [--fixtures ../shared/fixtures] [--raw out/sheet]

Needs the pip ``bpy`` module. The Avatar row wears every built-in item at least once
(``render_clothes.BODIES`` plus the facial hair); the MakeHuman row wears MakeHuman 1.1's CC0
clothes, shoes, hair, eyebrows and eyelashes from the shared fixtures (the row is left out
when they are absent). One Cycles render per row (all bodies side by side), identical camera,
lights and floor for both rows; a back view turns the bodies round in front of the same
camera and lights, so backs are lit as fronts are. Mid-motion is a quarter into the built-in
walk (legs apart, arms swung), the garments resolved for that frame as exports have them,
walking in place. Rows render with a transparent film and a shadow-catcher floor and are
laid onto one backdrop with Pillow, labelled. The raw row renders (full size, close-ups at
twice the sheet width) stay in ``--raw`` for zooming in.
"""

from __future__ import annotations

import argparse
import functools
import os
import sys
import tempfile
import textwrap
from dataclasses import dataclass
from pathlib import Path

import numpy as np

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="avatar-blender-"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from render_clothes import BODIES  # noqa: E402  (bench/ sibling)

NAMES = ("child", "teen", "woman", "man", "heavy woman", "muscular man", "elderly woman",
         "elderly man")  # fmt: skip
# Built-ins render_clothes.BODIES does not wear, added here so every item is worn once.
EXTRA = {3: ("stubble",), 5: ("beard-short",), 7: ("moustache",)}
# MakeHuman 1.1 CC0 assets per body (fixtures/makehuman/<kind>/<name>): a sensible outfit
# from what the fixtures hold (four suits, two pairs of shoes, one hairstyle).
FACE = ("hair/short02", "eyebrows/eyebrow001", "eyelashes/eyelashes01")
MAKEHUMAN = (
    ("clothes/male_casualsuit06", "clothes/shoes02"),  # child: T-shirt, jeans, sneakers
    ("clothes/female_sportsuit01", "clothes/shoes02"),  # teen: crop top, leggings
    ("clothes/female_casualsuit01", "clothes/shoes02"),  # woman: T-shirt, jeans
    ("clothes/male_casualsuit06", "clothes/shoes01"),  # man: T-shirt, jeans, leather shoes
    ("clothes/female_elegantsuit01", "clothes/shoes01"),  # heavy woman: blouse, skirt
    ("clothes/male_casualsuit06", "clothes/shoes02"),  # muscular man
    ("clothes/female_elegantsuit01", "clothes/shoes01"),  # elderly woman: blouse, skirt
    ("clothes/male_casualsuit06", "clothes/shoes01"),  # elderly man
)
VIEWS = ("front", "back", "closeup")
POSES = ("rest", "walk")
BACKDROP = (124, 127, 133)  # sRGB grey behind the rows (the world light's colour, darker)
CROWN = 1.8  # close-ups: every crown put at this height (m), so one camera frames all heads
# The frame spans this many body spacings more than the bodies: the A-pose arms of the
# tallest bodies at the ends (up to ~1.1 m) reach past their 0.8 m slot, and the camera looks
# on from a little to the side, so the last body's arm was cut at the frame's edge.
MARGIN = 0.8


@dataclass(frozen=True)
class Framing:
    """One camera for a view: metres between bodies, the frame's height and its middle (m),
    and the direction from the bodies to the camera."""

    spacing: float
    height: float
    middle: float
    direction: tuple[float, float, float]


FRAMINGS = {
    "full": Framing(0.8, 2.05, 0.98, (0.12, -1.0, 0.1)),
    "closeup": Framing(0.48, 0.5, CROWN - 0.17, (0.12, -1.0, 0.04)),
}


def outfits() -> list[tuple[dict[str, float], tuple[str, ...]]]:
    """(parameters, built-in names) of the eight bodies: render_clothes.BODIES and EXTRA."""
    return [(dict(p), tuple(names) + EXTRA.get(i, ())) for i, (p, names) in enumerate(BODIES)]


def makehuman_outfit(i: int, fixtures: Path) -> tuple[str, ...]:
    """``.mhclo`` paths of body ``i``'s MakeHuman outfit under ``fixtures``."""
    out = []
    for rel in MAKEHUMAN[i] + FACE:
        folder = fixtures / "makehuman" / rel
        out.append(str(folder / f"{folder.name}.mhclo"))
    return tuple(out)


def shown_parts(human, pose: str, view: str) -> list:
    """The human's MeshParts as still meshes: at rest or mid-stride (in place), turned
    round for the back view, crown at ``CROWN`` for close-ups."""
    from avatar.part import MeshPart
    from avatar.rig import skinning

    parts = _rest_parts(human)
    vertices = [p.mesh.vertices for p in parts]
    if pose == "walk":
        matrices = _mid_stride(human)
        body = skinning.linear_blend(human.vertices, human.weights, matrices)
        garments = human.outfit.frame(body, matrices, exact=True)
        count = len(parts) - len(garments)
        # Body parts through their own skin weights (the hidden skin changes their indices).
        vertices = [
            skinning.linear_blend(p.mesh.vertices, skinning.SkinWeights(*p.skin), matrices)
            for p in parts[:count]
        ] + list(garments)
        shift = np.zeros(3, np.float32)  # walk in place: keep the rest pose's ground spot
        shift[:2] = (body[:13380] - human.vertices[:13380]).mean(axis=0)[:2]
        vertices = [v - shift for v in vertices]
    turn = np.diag([-1.0, -1.0, 1.0]).astype(np.float32) if view == "back" else np.eye(3)
    lift = 0.0
    if view == "closeup":
        lift = CROWN - float(vertices[0][:, 2].max())
    out = []
    for p, v in zip(parts, vertices, strict=True):
        v = np.asarray(v, np.float32) @ turn.T + np.float32([0.0, 0.0, lift])
        normals = None if p.normals is None else p.normals @ turn.T
        out.append(MeshPart(p.name, p.mesh.with_vertices(v.astype(np.float32)), p.material,
                            p.skin, {}, normals))  # fmt: skip
    return out


@functools.cache
def _rest_parts(human) -> list:
    """body, eyes, teeth, tongue (MakeHuman-covered skin hidden), then the garments: made
    once per human (materials and fits), shared by its six renders."""
    return human.parts()


def _mid_stride(human) -> np.ndarray:
    """(J, 4, 4) skinning matrices a quarter into the built-in walk (frame 6 of 24)."""
    from avatar.rig import kinematics

    walk = human.walk(seconds=1.0, fps=24)
    world = kinematics.forward(human.skeleton, walk.rotations[6:7], walk.translations[6:7])
    return kinematics.skinning_matrices(human.skeleton, world)[0]


def row_size(view: str, count: int, width: int) -> tuple[int, int]:
    """(W, H) pixels of a row render: ``width`` wide (close-ups twice, to zoom in on)."""
    f = FRAMINGS["closeup" if view == "closeup" else "full"]
    w = width * 2 if view == "closeup" else width
    return w, max(8, round(w * f.height / (f.spacing * (count + MARGIN))))


def render_row(humans, view: str, pose: str, path: Path, width: int, samples: int) -> Path:
    """One Cycles render of ``humans`` side by side; transparent film, shadow-catcher floor."""
    from avatar.blender import render, scene

    f = FRAMINGS["closeup" if view == "closeup" else "full"]
    scene.clear_scene()
    n = len(humans)
    for i, human in enumerate(humans):
        x = (i - (n - 1) / 2) * f.spacing
        parts = shown_parts(human, pose, view)
        scene.build_character(scene.Character(f"body{i}", parts, None, location=(x, 0.0, 0.0)))
    scene.add_lights()
    floor = scene.add_floor()
    floor.is_shadow_catcher = True
    # Stop sampling smooth areas early (Cycles' default 0.01 is for finals): the rows stay
    # cheap on a shared CPU; the denoiser (16+ samples) cleans the rest.
    floor.users_scene[0].cycles.adaptive_threshold = 0.04
    size = row_size(view, n, width)
    _aim(f, n, size)
    return render.render(path, samples=samples, resolution=size, transparent=True)


def _aim(f: Framing, count: int, size: tuple[int, int]) -> None:
    """An 85 mm camera along -``f.direction`` framing ``count`` bodies' width."""
    from avatar.blender.camera import add_camera
    from avatar.camera import CameraModel, look_at

    back = np.asarray(f.direction, float)
    back /= np.linalg.norm(back)
    # half the 36 mm sensor spans half the row and its margin
    distance = f.spacing * (count + MARGIN) / 2 * 85.0 / 18.0
    centre = np.array([0.0, 0.0, f.middle])
    add_camera(CameraModel(85.0, 36.0, 24.0, "HORIZONTAL", 0.0, 0.0, size, 100, (1.0, 1.0),
                           look_at(centre + back * distance, centre)))  # fmt: skip


def compose(
    rows: list[tuple[str, Path, list[str]]], title: str, out: Path, width: int
) -> tuple[Path, list[tuple[int, int]]]:
    """Lay row renders (label, RGBA PNG, one caption per body) onto the backdrop, one under
    the other, labelled; write a ``width``-wide PNG. Returns it and each row picture's
    (top, bottom) in it."""
    from PIL import Image, ImageDraw

    big, small = _font(max(10, width // 80)), _font(max(8, width // 130))
    pictures = []
    for _, path, _ in rows:
        image = Image.open(path).convert("RGBA")
        scale = width / image.width
        pictures.append(image.resize((width, max(1, round(image.height * scale))),
                                     Image.Resampling.LANCZOS))  # fmt: skip
    pad = big.size + 8
    line = small.size + 2
    chars = max(8, int(width / len(rows[0][2]) / (small.size * 0.55)))
    captions = [[textwrap.wrap(c, chars, break_long_words=False) for c in caps]
                for _, _, caps in rows]  # fmt: skip
    caption_h = [line * max(len(c) for c in caps) + 6 for caps in captions]
    height = pad + sum(pad + p.height + h for p, h in zip(pictures, caption_h, strict=True))
    sheet = Image.new("RGB", (width, height), BACKDROP)
    draw = ImageDraw.Draw(sheet)
    draw.text((8, 4), title, fill=(245, 245, 245), font=big)
    y, boxes = pad, []
    for (label, _, caps), picture, wrapped, h in zip(rows, pictures, captions, caption_h,
                                                      strict=True):  # fmt: skip
        draw.rectangle((0, y, width, y + pad - 2), fill=(96, 98, 104))
        draw.text((8, y + 3), label, fill=(255, 255, 255), font=big)
        y += pad
        sheet.paste(picture, (0, y), picture)
        boxes.append((y, y + picture.height))
        y += picture.height
        column = width / len(caps)
        for i, lines in enumerate(wrapped):
            for k, text in enumerate(lines):
                draw.text((int(i * column) + 4, y + 2 + k * line), text, fill=(20, 20, 24),
                          font=small)  # fmt: skip
        y += h
    out.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(out, optimize=True)
    return out, boxes


def _font(size: int):
    from PIL import ImageFont

    for name in ("DejaVuSans.ttf", "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"):
        try:
            return ImageFont.truetype(name, size)
        except OSError:
            continue
    return ImageFont.load_default(size)


@dataclass(frozen=True)
class Row:
    """One row of a sheet: its label, one caption per body and the dressed humans."""

    label: str
    captions: list[str]
    humans: list


@dataclass(frozen=True)
class Sheet:
    """A composed sheet: its PNG, the raw row renders and each row's picture box in the
    sheet, (top, bottom) pixels."""

    path: Path
    rows: list[Path]
    boxes: list[tuple[int, int]]


def rows_for(bodies, indices: list[int], fixtures: Path | None) -> list[Row]:
    """The Avatar row of ``bodies`` (parameters, built-in names), then, when ``fixtures``
    holds MakeHuman's assets, the MakeHuman row: the same bodies in MAKEHUMAN[indices]."""
    from avatar.human import Human

    avatar = [Human(p).dressed(*names) for p, names in bodies]  # on their shoes' soles
    rows = [Row("Avatar: built-in garments, hair, brows, lashes, facial hair",
                [", ".join(n for n in names if not n.startswith("eye")) for _, names in bodies],
                avatar)]  # fmt: skip
    if fixtures is not None and (fixtures / "makehuman").is_dir():
        mh = [Human(p).dressed(*makehuman_outfit(i, fixtures))
              for (p, _), i in zip(bodies, indices, strict=True)]  # fmt: skip
        caps = [", ".join(Path(r).name.split("_")[-1] for r in MAKEHUMAN[i] + FACE[:1])
                for i in indices]  # fmt: skip
        rows.append(Row("MakeHuman 1.1 CC0 assets (shared fixtures), same bodies", caps, mh))
    return rows


def make_sheet(
    rows: list[Row],
    view: str,
    pose: str,
    out: Path,
    raw: Path,
    indices: list[int],
    width: int = 1200,
    samples: int = 16,
) -> Sheet:
    """Render each row (``view`` x ``pose``) and compose them into the sheet ``out``;
    ``indices``: which of the eight bodies the rows show (for the captions)."""
    shown = []
    for k, row in enumerate(rows):
        path = render_row(row.humans, view, pose, raw / f"{out.stem}_row{k}.png", width,
                          samples)  # fmt: skip
        named = [f"{NAMES[i]}: {c}" for i, c in zip(indices, row.captions, strict=True)]
        shown.append((row.label, path, named))
    title = (f"{'close-up (head and shoulders)' if view == 'closeup' else view}, "
             f"{'mid-stride (built-in walk)' if pose == 'walk' else 'rest'}; "
             f"Cycles {samples} spp")  # fmt: skip
    path, boxes = compose(shown, title, out, width)
    return Sheet(path, [p for _, p, _ in shown], boxes)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=16)
    parser.add_argument("--width", type=int, default=1200, help="sheet width, pixels")
    parser.add_argument("--out", default="docs/images")
    parser.add_argument("--raw", default="out/sheet", help="where the row renders stay")
    parser.add_argument("--views", default=",".join(VIEWS))
    parser.add_argument("--poses", default=",".join(POSES))
    parser.add_argument("--bodies", default="", help="e.g. 0,3: a subset of the eight")
    parser.add_argument(
        "--fixtures", default=str(Path(__file__).resolve().parents[2] / "shared" / "fixtures")
    )
    args = parser.parse_args()
    every = outfits()
    indices = [int(i) for i in args.bodies.split(",")] if args.bodies else list(range(8))
    fixtures = Path(args.fixtures)
    if not (fixtures / "makehuman").is_dir():
        print(f"no MakeHuman fixtures at {fixtures}: Avatar rows only")
    rows = rows_for([every[i] for i in indices], indices, fixtures)
    for pose in args.poses.split(","):
        for view in args.views.split(","):
            out = Path(args.out) / f"sheet_{view}_{pose}.png"
            make_sheet(rows, view, pose, out, Path(args.raw), indices, args.width, args.samples)
            print(out)


if __name__ == "__main__":
    main()
