"""The kinematics package's error, and the input checks that raise it, so that bad values never
reach Pinocchio.

:class:`KinematicsError` is raised for bad input to any kinematics function (wrong array shapes,
NaN or infinite angles, inconsistent configurations), always with one sentence naming the problem
and the fix, so that no bad value reaches Pinocchio and no silently wrong answer comes back.

Every public function of the package turns its array and number arguments into plain float
arrays here first: text, ``None``, ragged lists and complex numbers (whose imaginary part a cast
would silently drop) become one :class:`KinematicsError` sentence instead of a NumPy or Pinocchio
exception further down.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._errors import StudioError
from .._numbers import is_number

if TYPE_CHECKING:
    import numpy as np


class KinematicsError(StudioError):
    """Bad input to a kinematics model; ``str(err)`` says what is wrong and how to fix it."""


SIDES = ("right", "left")
"""The arms a tape can be strapped to (``human.urdf``'s link prefixes)."""

#: NumPy dtype kinds that hold real numbers (bool, signed and unsigned integers, floats).
_REAL_KINDS = "biuf"


def real_array(value: object, what: str, hint: str = "pass an array of real numbers") -> np.ndarray:
    """``value`` as a float64 array, or a KinematicsError naming ``what``.

    Args:
        value: anything array-like.
        what: the argument's name, for the message.
        hint: the fix the message suggests.

    Returns:
        A float64 array (a view of ``value`` when it already is one).

    Raises:
        KinematicsError: ``value`` is not an array of real numbers.
    """
    import numpy as np  # here: the robot list reads this module's error without loading numpy

    try:
        raw = np.asarray(value)
    except (TypeError, ValueError):  # ragged nested lists
        raise KinematicsError(f"{what} is not a numeric array; {hint}.") from None
    if raw.dtype.kind not in _REAL_KINDS:
        if raw.dtype.kind == "O":  # e.g. a list mixing numbers and None
            try:
                return raw.astype(float)
            except (TypeError, ValueError):
                pass
        kind = {"c": "complex numbers", "U": "text", "S": "bytes"}.get(
            raw.dtype.kind, f"{raw.dtype} values"
        )
        raise KinematicsError(f"{what} holds {kind}, not real numbers; {hint}.")
    return raw.astype(float, copy=False)


def positive_number(value: object, what: str) -> float:
    """``value`` as a finite float above zero, or a KinematicsError naming ``what``."""
    if not (is_number(value) and float(value) > 0):  # type: ignore[arg-type]
        raise KinematicsError(f"{what} must be a positive number; got {value!r}.")
    return float(value)  # type: ignore[arg-type]


def whole_number(value: object, what: str, minimum: int) -> int:
    """``value`` as an int of at least ``minimum``, or a KinematicsError naming ``what``.

    Floats with a whole value (``20.0``) are accepted; ``2.5``, ``inf``, NaN, text and bools are
    not.
    """
    if not (is_number(value) and int(value) == value and value >= minimum):  # type: ignore[arg-type, operator]
        raise KinematicsError(f"{what} must be a whole number >= {minimum}; got {value!r}.")
    return int(value)  # type: ignore[call-overload]


def instance_of(value: object, kind: type, what: str, *, optional: bool = False) -> None:
    """Refuse a ``value`` that is not a ``kind`` (or None, when ``optional``) in one sentence.

    Args:
        value: the argument.
        kind: the class it must be.
        what: the argument's name, for the message (``"ArmFitter's arm"``).
        optional: None is allowed (the caller then builds a default).

    Raises:
        KinematicsError: naming ``what``, the type given and the fix.
    """
    if value is None and optional:
        return
    if not isinstance(value, kind):
        fix = " or leave it out" if optional else ""
        raise KinematicsError(
            f"{what} must be a {kind.__name__}, got {type(value).__name__}; "
            f"pass {kind.__name__}(...){fix}."
        )


def check_side(side: object, what: str) -> str:
    """``side`` when it names an arm (see :data:`SIDES`), else a KinematicsError naming ``what``.

    The one check of a taped arm's side, for the arm model, the tape and the operator's meshes.
    """
    if not isinstance(side, str) or side not in SIDES:
        raise KinematicsError(
            f'{what} must be "right" or "left"; got {side!r}, so give one of those.'
        )
    return side
