"""The built-in wardrobe: garments cut from the body's own helper geometry.

Each entry is a short recipe (which faces, how much ease, fabric, colour, thickness,
layer); ``build(name, body)`` turns it into a Garment bound to the base mesh, so it follows
every body from babies to old people. Nothing is downloaded: the geometry comes from the
MakeHuman base mesh Avatar already needs, the textures from ``fabrics``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from avatar.clothes import face, hair, shoes
from avatar.clothes.authoring import (
    AuthoringBody,
    Piece,
    banded,
    bound,
    covered_skin,
    cut,
    join,
)
from avatar.clothes.fitting import Garment
from avatar.clothes.regions import face_features
from avatar.looks import fabrics, facial_hair, textures
from avatar.material import Material

RELAX = 12  # smoothing passes over cut edges (hems, armholes, necklines)


@dataclass(frozen=True)
class Spec:
    """A built-in garment's recipe."""

    name: str
    category: str  # tops, bottoms, dresses, swimwear, legwear, footwear, headwear, hair, face
    make: Callable[[AuthoringBody], Piece]
    fabric: str
    colour: str
    thickness: float
    z_depth: int
    tags: tuple[str, ...] = ()
    collide: bool = True
    # (spec, texture size) -> Material, for garments of several materials in one atlas.
    look: Callable[[Spec, int], Material] | None = None


def _tights(body: AuthoringBody, keep_fn, ease, band: float = 0.0) -> Piece:
    """A garment cut from ``helper-tights``; ``band`` > 0: a rib/hem band that wide (m)
    along every open edge (``authoring.banded``)."""
    faces = body.group_faces("helper-tights")
    ff = face_features(body.vertices, faces, body.part, body.marks)
    mesh = cut(body, faces, keep_fn(ff, body.marks), ease, relax=RELAX)
    if band:
        mesh = banded(mesh, band)
    return bound(body, mesh, faces)


def _skirt(body: AuthoringBody, bottom_z: float, ease) -> Piece:
    faces = body.group_faces("helper-skirt")
    centre_z = body.vertices[faces].mean(axis=1)[:, 2]
    return bound(body, cut(body, faces, centre_z > bottom_z, ease, RELAX, loose=True), faces)


def _z(ff):
    return ff.centre[:, 2]


def top(sleeve: float, neck: float = 0.0, hem: float = 0.04):
    """Torso above the hip line (+hem), sleeves to ``sleeve`` along the arm."""

    def keep(ff, m):
        # Upper-thigh faces too, so a long top's hem runs level instead of following the groin.
        trunk = (ff.part == "torso") | (ff.part == "leg")
        torso = trunk & (_z(ff) > m.hip[0, 2] + hem) & (_z(ff) < m.neck[2] - neck)
        return torso | ((ff.part == "arm") & (ff.arm < sleeve))

    return keep


def opened(keep_fn, gap: float = 0.012):
    """A front opening: ``keep_fn``'s faces less a strip ``gap`` m either side of the
    body's midline on the front (a jacket or cardigan worn open)."""

    def keep(ff, m):
        front = ff.centre[:, 1] < m.neck[1] + 0.01  # the neck's front too: open to the collar
        return keep_fn(ff, m) & ~(front & (np.abs(ff.centre[:, 0]) < gap))

    return keep


def bottom(length: float, rise: float = 0.07):
    """Pelvis up to ``rise`` above the hip joints, legs to ``length`` along the leg."""

    def keep(ff, m):
        pelvis = (ff.part == "torso") & (_z(ff) < m.hip[0, 2] + rise)
        return pelvis | ((ff.part == "leg") & (ff.leg < length))

    return keep


def strapped(hem: float, armhole: float = 0.062, front: float = 0.12, back: float = 0.05):
    """Torso on straps down to ``hem`` m above the hip joints: a neckline scooped ``front``
    and ``back`` m below the neck joint, oval armholes ``armhole`` m in from the shoulder
    joint reaching a hand's width below it (shoulder faces count as arm)."""

    def keep(ff, m):
        x, y, z = ff.centre.T
        across, shoulder_x = np.abs(x), abs(m.shoulder[0, 0])
        hole = ((across - shoulder_x) / armhole) ** 2 + ((z - m.shoulder[0, 2] - 0.05) / 0.15) ** 2
        depth = np.where(y < m.neck[1], front, back)
        neckline = m.neck[2] - depth * np.sqrt(np.clip(1 - (across / 0.07) ** 2, 0, 1))
        upper = (ff.part == "torso") | ((ff.part == "arm") & (across < shoulder_x - 0.03))
        body = upper & (z > m.hip[0, 2] + hem) & (hole > 1) & (across < shoulder_x)
        return body & ~((across < 0.07) & (z > neckline))

    return keep


tank = strapped(0.04)
# A one-piece: high-cut legs (the torso faces end at the groin), narrow straps, deep neck.
swimsuit = strapped(-0.15, armhole=0.072, front=0.15, back=0.13)


def socks(ff, m):
    return (ff.part == "foot") | ((ff.part == "leg") & (ff.leg > 0.78))


def bodice(ff, m):
    return (ff.part == "torso") & (_z(ff) > m.hip[0, 2] + 0.02) & (_z(ff) < m.chest_z + 0.12)


def flare(base: float, extra: float, start: float = 0.0):
    """Ease growing down a limb (trouser legs hang straight from the widest part)."""
    return lambda p, arm, leg: base + extra * np.clip((leg - start) / (1 - start), 0, 1)


def sleeve_ease(base: float, extra: float):
    return lambda p, arm, leg: base + extra * np.clip(arm, 0, 1)


def shoe_look(upper: str, upper_colour: str, sole_colour: str, lace_colour: str,
              cap_colour: str | None = None):  # fmt: skip
    """A shoe's atlas material (``shoes.ROWS``): upper, toe cap, sole and laces."""

    def look(spec: Spec, size: int) -> Material:
        rows = shoes.ROWS
        return fabrics.atlas(spec.name, [
            (*rows["upper"], upper, upper_colour),
            (*rows["cap"], upper, cap_colour or upper_colour),
            (*rows["sole"], "rubber", sole_colour),
            (*rows["laces"], "cord", lace_colour),
        ], size, stitches=(0.5 + 0.5 * 0.12, 0.3 + 0.2 * 0.2))  # fmt: skip

    return look


# A dress's bodice: the tank top's cut on wider straps, its neckline scooped 9 cm below the
# neck joint in front (well above the bust at every size) and 7 cm at the back.
dress_bodice = strapped(0.02, armhole=0.056, front=0.09, back=0.07)


def _dress(body: AuthoringBody) -> Piece:
    top_piece = _tights(body, dress_bodice, 0.004, 0.012)
    skirt_piece = _skirt(body, body.marks.knee[0, 2] - 0.12, _skirt_ease(body, 0.004, 0.05))
    return join([top_piece, skirt_piece])


def _hood(body: AuthoringBody) -> Piece:
    """A hood lying down on the back: the back of the neck and shoulders cut again and
    puffed out into a soft roll (deepest in the middle), its rim banded."""
    faces = body.group_faces("helper-tights")
    m = body.marks
    c = body.vertices[faces].mean(axis=1)
    low, high = m.neck[2] - 0.2, m.neck[2] + 0.035
    keep = (c[:, 1] > m.neck[1] - 0.01) & (c[:, 2] > low) & (c[:, 2] < high)
    keep &= np.abs(c[:, 0]) < 0.14

    def puff(p, arm, leg):
        across = np.clip(1 - (p[:, 0] / 0.14) ** 2, 0, 1)
        down = np.sin(np.pi * np.clip((p[:, 2] - low) / (high - low), 0, 1)) ** 0.7
        return 0.012 + 0.035 * across * down

    return bound(body, banded(cut(body, faces, keep, puff, relax=RELAX), 0.012), faces)


def _hoodie(body: AuthoringBody) -> Piece:
    top_piece = _tights(body, top(0.95, neck=-0.02, hem=-0.02), sleeve_ease(0.013, 0.012), 0.03)
    return join([top_piece, _hood(body)])


def _skirt_ease(body: AuthoringBody, base: float, extra: float):
    hip, knee = body.marks.hip[0, 2], body.marks.knee[0, 2]
    return lambda p, arm, leg: base + extra * np.clip((hip - p[:, 2]) / (hip - knee), 0, 1.5)


def _cap(body: AuthoringBody) -> Piece:
    crown = hair.scalp(body, 0.014, front=0.045, side=0.035, back=0.0)
    return join([crown, hair.brim(body, crown)])


EYELASH_GROUPS = (
    "helper-l-eyelashes-1",
    "helper-l-eyelashes-2",
    "helper-r-eyelashes-1",
    "helper-r-eyelashes-2",
)

SPECS = [
    Spec("tshirt", "tops", lambda b: _tights(b, top(0.3), sleeve_ease(0.007, 0.02), 0.014), "cotton", "white", 0.0015, 40, ("t-shirt", "short sleeve", "casual")),  # noqa: E501
    Spec("longsleeve", "tops", lambda b: _tights(b, top(0.94), sleeve_ease(0.006, 0.012), 0.02), "jersey", "navy", 0.0015, 40, ("long sleeve", "shirt")),  # noqa: E501
    Spec("tanktop", "tops", lambda b: _tights(b, tank, 0.004), "jersey", "grey", 0.0012, 40, ("tank top", "vest", "sleeveless")),  # noqa: E501
    Spec("jacket", "tops", lambda b: _tights(b, opened(top(0.95, neck=-0.03, hem=-0.03), 0.02), sleeve_ease(0.016, 0.01), 0.02), "leather", "black", 0.003, 60, ("jacket", "outerwear", "open")),  # noqa: E501
    Spec("cardigan", "tops", lambda b: _tights(b, opened(top(0.94, neck=-0.01, hem=-0.05), 0.022), sleeve_ease(0.012, 0.01), 0.025), "knit", "beige", 0.003, 58, ("cardigan", "knit", "elderly", "open")),  # noqa: E501
    Spec("hoodie", "tops", _hoodie, "knit", "grey", 0.004, 55, ("hoodie", "sweater", "knit")),  # noqa: E501
    Spec("shorts", "bottoms", lambda b: _tights(b, bottom(0.4), flare(0.007, 0.02)), "canvas", "khaki", 0.002, 35, ("shorts",)),  # noqa: E501
    Spec("trousers", "bottoms", lambda b: _tights(b, bottom(0.97), flare(0.008, 0.025, 0.2)), "wool", "grey", 0.002, 35, ("trousers", "pants", "formal")),  # noqa: E501
    Spec("jeans", "bottoms", lambda b: _tights(b, bottom(0.96), flare(0.005, 0.012, 0.3)), "denim", "indigo", 0.0025, 35, ("jeans", "denim", "pants")),  # noqa: E501
    Spec("sweatpants", "bottoms", lambda b: _tights(b, bottom(0.95), flare(0.012, 0.02, 0.1), 0.03), "jersey", "grey", 0.002, 35, ("sweatpants", "joggers", "children", "elderly")),  # noqa: E501
    Spec("leggings", "bottoms", lambda b: _tights(b, bottom(0.95), 0.0015), "lycra", "black", 0.001, 25, ("leggings", "sport")),  # noqa: E501
    Spec("skirt", "bottoms", lambda b: _skirt(b, b.marks.knee[0, 2] + 0.1, _skirt_ease(b, 0.004, 0.03)), "cotton", "red", 0.0015, 36, ("skirt",)),  # noqa: E501
    Spec("dress", "dresses", _dress, "cotton", "teal", 0.0015, 38, ("dress",)),
    Spec("swimsuit", "swimwear", lambda b: _tights(b, swimsuit, 0.001), "lycra", "sky", 0.001, 25, ("swimwear", "one-piece")),  # noqa: E501
    Spec("socks", "legwear", lambda b: _tights(b, socks, 0.0015), "knit", "white", 0.0015, 20, ("socks",)),  # noqa: E501
    Spec("shoes", "footwear", shoes.shoes, "leather", "brown", 0.0025, 30, ("shoes", "leather", "laced"), look=shoe_look("calf", "brown", "charcoal", "cream", "dark brown")),  # noqa: E501
    Spec("shoes-black", "footwear", shoes.shoes, "leather", "black", 0.0025, 30, ("shoes", "formal", "laced"), look=shoe_look("calf", "black", "black", "black", "charcoal")),  # noqa: E501
    Spec("sneakers", "footwear", shoes.shoes, "canvas", "white", 0.0025, 30, ("sneakers", "trainers", "children", "sport"), look=shoe_look("canvas", "white", "white", "white", "grey")),  # noqa: E501
    Spec("boots", "footwear", lambda b: shoes.shoes(b, top=0.86), "leather", "brown", 0.0025, 30, ("boots", "ankle boots", "laced"), look=shoe_look("calf", "dark brown", "black", "tan", "dark brown")),  # noqa: E501
    Spec("cap", "headwear", _cap, "canvas", "red", 0.003, 80, ("cap", "hat", "baseball")),
    Spec("hair-short", "hair", lambda b: join([hair.base_cap(b), hair.grow_cards(b, hair.flow_crown())]), "hair", "dark brown hair", 0.0, 70, ("hair", "short")),  # noqa: E501
    Spec("hair-long", "hair", lambda b: join([hair.base_cap(b), hair.grow_cards(b, hair.flow_parted(), 300, (0.1, 0.16), 0.025, (0.004, 0.012), 4), hair.long_cards(b)]), "hair", "blond hair", 0.0, 70, ("hair", "long")),  # noqa: E501
    Spec("hair-ponytail", "hair", lambda b: join([hair.base_cap(b), hair.grow_cards(b, hair.flow_tied(), 320, (0.08, 0.14), 0.025, (0.003, 0.008), 4), hair.ponytail(b)]), "hair", "black hair", 0.0, 70, ("hair", "tied back", "ponytail")),  # noqa: E501
    Spec("hair-buzz", "hair", lambda b: join([hair.base_cap(b, 0.0015), hair.grow_cards(b, hair.flow_crown(sweep=0.0), 1400, (0.006, 0.012), 0.008, (0.0015, 0.003), 2)]), "hair", "dark brown hair", 0.0, 70, ("hair", "buzz", "short", "men")),  # noqa: E501
    Spec("hair-bob", "hair", lambda b: join([hair.base_cap(b), hair.grow_cards(b, hair.flow_parted(), 300, (0.06, 0.1), 0.025, (0.004, 0.014), 4), hair.hang_cards(b, hair.flow_parted())]), "hair", "auburn hair", 0.0, 70, ("hair", "bob", "fringe")),  # noqa: E501
    Spec("hair-bun", "hair", lambda b: join([hair.base_cap(b), hair.grow_cards(b, hair.flow_tied((0.0, 0.06, 0.075)), 360, (0.08, 0.14), 0.025, (0.003, 0.007), 4), hair.bun(b)]), "hair", "grey hair", 0.0, 70, ("hair", "bun", "tied back", "elderly")),  # noqa: E501
    Spec("eyebrows", "face", face.eyebrows, "hair", "dark brown hair", 0.0, 5, ("eyebrows",), False),  # noqa: E501
    Spec("eyebrows-blond", "face", face.eyebrows, "hair", "blond hair", 0.0, 5, ("eyebrows", "blond"), False),  # noqa: E501
    Spec("eyebrows-black", "face", face.eyebrows, "hair", "black hair", 0.0, 5, ("eyebrows", "black"), False),  # noqa: E501
    Spec("eyelashes", "face", lambda b: face.eyelashes(b, EYELASH_GROUPS), "hair", "black hair", 0.0, 5, ("eyelashes",), False),  # noqa: E501
    Spec("beard-short", "beard", face.beard, "hair", "dark brown", 0.0, 6, ("beard", "facial hair", "men"), look=facial_hair.beard_material),  # noqa: E501
    Spec("moustache", "beard", face.moustache, "hair", "dark brown", 0.0, 6, ("moustache", "mustache", "facial hair", "men"), look=facial_hair.beard_material),  # noqa: E501
    Spec("stubble", "beard", face.stubble, "hair", "black hair", 0.0, 4, ("stubble", "facial hair", "men"), False, look=facial_hair.stubble_material),  # noqa: E501
]  # fmt: skip

BY_NAME = {s.name: s for s in SPECS}


def build(spec: Spec, body: AuthoringBody, texture_size: int = 1024) -> Garment:
    """A built-in Garment from its recipe on the authoring body."""
    piece = spec.make(body)
    if spec.look is not None:
        material = spec.look(spec, texture_size)
    elif spec.category in ("hair", "face"):
        material = textures.hair_material(spec, texture_size)
    else:
        material = fabrics.material(spec.fabric, spec.colour, texture_size, name=spec.name)
    # Face proxies are drawn on the skin; holes there would show through, so they hide nothing.
    delete = covered_skin(body, piece.mesh) if spec.collide else np.zeros(0, np.int32)
    return Garment(
        name=spec.name,
        mesh=piece.mesh,
        binding=piece.binding,
        material=material,
        z_depth=spec.z_depth,
        delete_verts=delete,
        thickness=spec.thickness,
        collide=spec.collide,
        category=spec.category,
        tags=spec.tags,
        source="builtin",
        licence="CC0 (generated by Avatar from MakeHuman's CC0 base mesh)",
    )
