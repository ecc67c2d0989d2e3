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


# Blender's sidebar at its default width (Blender 3.4-5.0, UI scale 1, measured on the real
# window's screenshot, tests/ui): the report box's rows are split at LABEL_SHARE; its label
# column shows LABEL_PX of text and its value column VALUE_PX, in the UI font at 11 pt.
# Wider text is cut off with an ellipsis (with labels of 10 characters and an icon each,
# they were cut to two: "So...", "Di..."), so labels are short words, rows carry no icon
# (an alert row is drawn red) and numbers are formatted to fit
# (tests/blender/test_motion_panel.py measures the worst case with blf).
LABEL_SHARE = 0.34
LABEL_PX = 46
VALUE_PX = 100  # "30 frames, 120 fps" (100 px) showed whole; 102 px was cut
NAMED = ("Source", "Worst", "Stretch")  # values that are names: a long one may be cut


def lines(data: dict) -> list[tuple[str, str, bool]]:
    """(label, value, alert) rows of a ``card`` for display, in reading order, short enough
    for Blender's sidebar at its default width (``LABEL_PX``, ``VALUE_PX``)."""
    rows = [("Clip", f"{data.get('frames', 0)} at {data.get('fps', 0):.0f} fps", False),
            ("Source", str(data.get("source", "?")), False),
            ("Bones", f"{data.get('mapped', 0)}, scale {data.get('scale', 1.0):.2f}", False)]
    if "direction_median" in data:
        p95 = data["direction_p95"]
        rows.append(("Error", f"{_deg(data['direction_median'])} (p95 {_deg(p95)})",
                     p95 > DIRECTION_ALERT_DEG))  # fmt: skip
        if data.get("worst_bone"):
            rows.append(("Worst", f"{data['worst_bone']} {data['worst_deg']:.0f}\u00b0",
                         data["worst_deg"] > DIRECTION_ALERT_DEG))  # fmt: skip
        rows.append(("Skating", f"{_num(data['skating_cm'])} cm/frame",
                     data["skating_cm"] > SKATING_ALERT_CM))  # fmt: skip
        bent = data["limit_violations"]
        rows.append(("Limits", f"{bent} bent back" if bent else "none bent back", bent > 0))
    if "floor_penetration_cm" in data:
        rows.append(("Floor", f"{_num(data['floor_penetration_cm'])} cm in "
                     f"{data['floor_penetrating'] * 100:.0f}%",
                     data["floor_penetration_cm"] > FLOOR_ALERT_CM))  # fmt: skip
        rows.append(("Hover", f"{_num(data['hover_cm'])} cm, max {_num(data['hover_max_cm'])}",
                     data["hover_cm"] > HOVER_ALERT_CM))  # fmt: skip
    elif "feet_below_cm" in data:
        rows.append(("Floor", f"feet {_num(data['feet_below_cm'])} cm below",
                     data["feet_below_cm"] > FLOOR_ALERT_CM))  # fmt: skip
    if data.get("deformed"):
        more = len(data["deformed"]) - 1
        rows.append(("Stretch", data["deformed"][0] + (f" +{more}" if more else ""), True))
    return rows


def _num(x: float) -> str:
    """A measure in as many digits as fit: 0.12, 12.3, 123."""
    return f"{x:.2f}" if abs(x) < 10 else f"{x:.1f}" if abs(x) < 100 else f"{x:.0f}"


def _deg(x: float) -> str:
    return (f"{x:.1f}" if abs(x) < 10 else f"{x:.0f}") + "\u00b0"
