"""Export presets: named sets of the glTF options for a purpose (``avatar create --preset``).

    full   every texture at its made size, up to 8 joints per vertex, no LODs: renders,
           offline work, Blender.
    game   a game engine's budget: at most 4 joints per vertex (one JOINTS set, what
           three.js, Unity and Unreal read), textures capped at 1024 px (a 2K/1K budget:
           no map exceeds 1K, the skin included), 2 levels of detail (each half the
           triangles of the one before).

Options given on their own (``--max-influences``, ``--texture-size``, ``--lods``) win
over the preset's. In Python: ``avatar.save(human, path, **export_options("game"))``.
"""

from __future__ import annotations

from typing import Any

from avatar.errors import ParameterError, unknown_name

PRESETS: dict[str, dict[str, Any]] = {
    "full": {"max_influences": 8, "texture_size": None, "lods": 0},
    "game": {"max_influences": 4, "texture_size": 1024, "lods": 2},
}


def export_options(preset: str | None = "full", **given: Any) -> dict[str, Any]:
    """The export keyword arguments of a preset (default "full"), with the ``given`` ones
    that are not None taking their place. Raises ParameterError for an unknown preset or
    an option no preset has."""
    name = preset or "full"
    if name not in PRESETS:
        raise unknown_name("preset", name, list(PRESETS))
    unknown = set(given) - set(PRESETS[name])
    if unknown:
        raise ParameterError(f"not an export preset option: {', '.join(sorted(unknown))}")
    return PRESETS[name] | {k: v for k, v in given.items() if v is not None}
