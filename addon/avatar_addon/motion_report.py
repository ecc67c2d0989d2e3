"""The retarget quality a character keeps, as rows for the Motion panel's report box."""

from __future__ import annotations

import json

LABEL_SHARE = 0.34  # of a row for its label (avatar.motion.report_card.LABEL_SHARE)


def rows(root) -> list[tuple[str, str, bool]]:
    """(label, value, alert) rows of the last motion's report on ``root``: its numbers
    (``avatar.motion.report_card``) when stored, else the summary's lines; [] for none."""
    card = root.get("avatar_motion_card")
    if card:
        try:
            from avatar.motion import report_card

            return report_card.lines(json.loads(card))
        except (ImportError, ValueError, KeyError, TypeError):
            pass  # an older or damaged record: show the summary instead
    summary = root.get("avatar_motion_report")
    return [("", line, False) for line in str(summary).splitlines()[:14]] if summary else []
