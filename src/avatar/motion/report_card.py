"""A retarget's quality as the few numbers an animator reads, JSON-able so a character
can keep them (the Blender extension stores them on the character and shows them).

    card = report_card.card(report)              # dict of plain numbers and strings
    for label, value, alert in report_card.lines(card): ...

Thresholds for ``alert`` (a value worth a look): direction error p95 over 15 degrees,
skating over 1 cm a contact frame, feet or skin over 1 cm into the floor, feet hovering
over 2 cm, any knee or elbow bent backwards, any bone whose skin stretches over its limit.
"""

from __future__ import annotations

from avatar.motion.retarget import RetargetReport

DIRECTION_ALERT_DEG = 15.0
SKATING_ALERT_CM = 1.0
FLOOR_ALERT_CM = 1.0
HOVER_ALERT_CM = 2.0


def card(report: RetargetReport) -> dict:
    """The report's numbers (floats in degrees and cm) and notes; keys are absent for what
    was not measured (``quality`` None, no ``floor``)."""
    out: dict = {
        "source": report.source_convention,
        "target": report.target_convention,
        "mapped": len(report.mapped),
        "unused_source": len(report.unused_source),
        "scale": round(float(report.scale), 4),
        "frames": int(report.frames),
        "fps": round(float(report.fps), 3),
        "notes": list(report.notes),
    }
    q = report.quality
    if q is not None:
        worst = max(q.per_bone, key=q.per_bone.__getitem__, default="")
        out.update(
            direction_median=round(q.direction_median, 3),
            direction_p95=round(q.direction_p95, 3),
            direction_max=round(q.direction_max, 3),
            worst_bone=worst,
            worst_deg=round(q.per_bone.get(worst, 0.0), 3),
            skating_cm=round(q.skating_cm, 3),
            contact_frames=int(q.contact_frames),
            feet_below_cm=round(q.penetration_cm, 3),
            limit_violations=int(q.limit_violations),
            deformed=list(q.deformed),
        )
    if report.floor is not None:
        f = report.floor
        out.update(
            floor_penetration_cm=round(f.penetration_cm, 3),
            floor_penetrating=round(f.penetrating, 4),
            hover_cm=round(f.hover_cm, 3),
            hover_max_cm=round(f.hover_max_cm, 3),
        )
    return out


LABEL_CHARS = 10  # what the sidebar's label column shows at its default width
VALUE_CHARS = 24  # and its value column: longer text is cut off with an ellipsis


def lines(data: dict) -> list[tuple[str, str, bool]]:
    """(label, value, alert) rows of a ``card`` for display, in reading order: labels of at
    most ``LABEL_CHARS`` and values of at most ``VALUE_CHARS`` characters, so that nothing
    is cut off in Blender's sidebar at its default width."""
    rows = [("Clip", f"{data.get('frames', 0)} frames, {data.get('fps', 0):.0f} fps", False),
            ("Source", str(data.get("source", "?")), False),
            ("Mapping", f"{data.get('mapped', 0)} bones, scale {data.get('scale', 1.0):.2f}",
             False)]  # fmt: skip
    if "direction_median" in data:
        p95 = data["direction_p95"]
        rows.append(("Direction", f"{data['direction_median']:.1f}\u00b0 (p95 {p95:.1f}\u00b0)",
                     p95 > DIRECTION_ALERT_DEG))  # fmt: skip
        if data.get("worst_bone"):
            rows.append(("Worst bone", f"{data['worst_bone']} {data['worst_deg']:.0f}\u00b0",
                         data["worst_deg"] > DIRECTION_ALERT_DEG))  # fmt: skip
        rows.append(("Skating", f"{data['skating_cm']:.2f} cm/frame "
                     f"({data['contact_frames']})", data["skating_cm"] > SKATING_ALERT_CM))
        bent = data["limit_violations"]
        rows.append(("Limits", f"{bent} frames bent back" if bent else "none bent back",
                     bent > 0))  # fmt: skip
    if "floor_penetration_cm" in data:
        rows.append(("Floor", f"{data['floor_penetration_cm']:.2f} cm below, "
                     f"{data['floor_penetrating'] * 100:.0f}%",
                     data["floor_penetration_cm"] > FLOOR_ALERT_CM))  # fmt: skip
        rows.append(("Hover", f"{data['hover_cm']:.2f} cm, max {data['hover_max_cm']:.2f}",
                     data["hover_cm"] > HOVER_ALERT_CM))  # fmt: skip
    elif "feet_below_cm" in data:
        rows.append(("Floor", f"feet {data['feet_below_cm']:.2f} cm below",
                     data["feet_below_cm"] > FLOOR_ALERT_CM))  # fmt: skip
    if data.get("deformed"):
        more = len(data["deformed"]) - 1
        rows.append(("Stretch", data["deformed"][0] + (f" +{more}" if more else ""), True))
    return [(label, _fit(value), alert) for label, value, alert in rows]


def _fit(value: str) -> str:
    return value if len(value) <= VALUE_CHARS else value[: VALUE_CHARS - 1] + "\u2026"
