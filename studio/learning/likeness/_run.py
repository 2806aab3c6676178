"""A run's likeness cards: its policy against each recorded demonstration it was taught from.

``likeness.json`` in the run folder, written when a run of recorded demonstrations finishes::

    {"format": "teach-studio-likeness", "version": 2, "policy": "policy.policy.npz",
     "cards": [{"demonstration": "reach-1", "card": {...LikenessCard.to_dict()...}},
               {"demonstration": "reach-2", "error": "one sentence"}]}

Each card rolls the policy out from that demonstration's own start
(:func:`policy_likeness_card`); the page's Watch and ``studio export`` score the same way.
Version 2: each card's ``ldlj`` is the tool path's, low-passed (``_likeness.LDLJ_CUTOFF_HZ``),
and beside it is the tool's ``sparc``; version 1 files hold the joints' LDLJ, unfiltered, which
the tape's noise dominated, and no SPARC.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Sequence
from pathlib import Path

from ..._files import atomic_write_text
from .._errors import LearningError
from .._registry import AnyPolicy, load_any_policy
from ..tasks._demo_motion import DemonstrationMotion
from ._likeness import LikenessCard
from ._policy import policy_likeness_card

log = logging.getLogger(__name__)

LIKENESS_FILE = "likeness.json"
"""The run folder's likeness cards."""
LIKENESS_FORMAT = "teach-studio-likeness"
LIKENESS_VERSION = 2
"""2 since the card's LDLJ is the tool path's, low-passed (1: the joints', unfiltered)."""


def likeness_cards(
    policy: AnyPolicy,
    motions: Sequence[DemonstrationMotion],
) -> list[tuple[DemonstrationMotion, LikenessCard | str]]:
    """Each demonstration with the policy's card against it, or the sentence saying why none."""
    out: list[tuple[DemonstrationMotion, LikenessCard | str]] = []
    for motion in motions:
        try:
            out.append((motion, policy_likeness_card(policy, motion.times, motion.q_robot)))
        except LearningError as err:
            out.append((motion, str(err)))
    return out


def likeness_document(
    policy: AnyPolicy,
    motions: Sequence[DemonstrationMotion],
    policy_name: str = "",
) -> dict[str, object]:
    """``likeness.json``'s object (the module docstring) for ``policy`` against ``motions``."""
    cards: list[dict[str, object]] = []
    for motion, card in likeness_cards(policy, motions):
        if isinstance(card, str):
            cards.append({"demonstration": motion.name, "error": card})
        else:
            cards.append({"demonstration": motion.name, "card": card.to_dict()})
    return {
        "format": LIKENESS_FORMAT,
        "version": LIKENESS_VERSION,
        "policy": policy_name,
        "cards": cards,
    }


def save_run_likeness(
    folder: Path, policy_path: Path, motions: Sequence[DemonstrationMotion]
) -> Path | None:
    """Write ``folder/likeness.json`` for the run's policy; None (logged) when it cannot be
    written: a card is a report, never a reason to fail a finished run."""
    if not motions:
        return None
    try:
        document = likeness_document(load_any_policy(policy_path), motions, policy_path.name)
        return atomic_write_text(folder / LIKENESS_FILE, json.dumps(document, indent=1) + "\n")
    except (LearningError, OSError) as err:
        log.warning("%s: no likeness card written: %s", folder.name, err)
        return None
