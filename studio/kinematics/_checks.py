"""The kinematics package's error, and the input checks that raise it, so that bad values never
reach Pinocchio.

:class:`KinematicsError` is raised for bad input to any kinematics function (wrong array shapes,
NaN or infinite angles, inconsistent configurations), always with one sentence naming the problem
and the fix, so that no bad value reaches Pinocchio and no silently wrong answer comes back.

Every public function of the package turns its array and number arguments into plain float
arrays here first: text, ``None``, ragged lists and complex numbers (whose imaginary part a cast
would silently drop) become one :class:`KinematicsError` sentence instead of a NumPy or Pinocchio
exception further down.

Also here, the box a task keeps the arm away from (:class:`Obstacle`) and its checks: a light
module, so ``studio train --obstacle`` reads the box before any collision model loads.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

from .._errors import StudioError
from .._numbers import is_number, is_real

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


# --------------------------------------------------------------------------------- obstacles

MAX_OBSTACLES = 16
"""Most boxes a task may hold."""
MAX_OBSTACLE_REACH_M = 10.0
"""No box's centre lies further than this from the robot's base, nor is any side longer (m)."""


@dataclass(frozen=True)
class Obstacle:
    """A box in the robot's base frame: its centre and its full sizes along x, y and z (m).

    ``Obstacle.parse("0.5,-0.2,0.9,0.2,0.2,0.4")`` reads the ``--obstacle`` form.
    """

    centre: tuple[float, float, float]
    size: tuple[float, float, float]

    def __post_init__(self) -> None:
        values = _obstacle_numbers([*self.centre, *self.size], f"The obstacle {self}")
        object.__setattr__(self, "centre", tuple(values[:3]))
        object.__setattr__(self, "size", tuple(values[3:]))

    @classmethod
    def parse(cls, text: str) -> Obstacle:
        """The box of ``CX,CY,CZ,SX,SY,SZ`` (centre, then full sizes, metres).

        Raises:
            KinematicsError: not six finite numbers, or a size not above zero.
        """
        parts = str(text).split(",")
        try:
            values = [float(v) for v in parts]
        except ValueError:
            values = []
        if len(values) != 6:
            raise KinematicsError(
                f"The obstacle {text!r} is not six numbers; give its centre and full sizes in "
                "metres as CX,CY,CZ,SX,SY,SZ, e.g. 0.5,-0.2,0.9,0.2,0.2,0.4."
            )
        return cls((values[0], values[1], values[2]), (values[3], values[4], values[5]))

    @classmethod
    def from_value(cls, value: object, what: str = "An obstacle") -> Obstacle:
        """The box of :meth:`to_dict`'s form (``{"centre": [x, y, z], "size": [x, y, z]}``), or of
        six numbers in a list.

        Raises:
            KinematicsError: any other value.
        """
        if isinstance(value, Obstacle):
            return value
        if isinstance(value, dict) and set(value) == {"centre", "size"}:
            value = [*_three(value["centre"], what), *_three(value["size"], what)]
        if not isinstance(value, list | tuple) or len(value) != 6:
            raise KinematicsError(
                f'{what} is {value!r}; give {{"centre": [x, y, z], "size": [x, y, z]}} in metres.'
            )
        values = _obstacle_numbers(value, what)
        return cls((values[0], values[1], values[2]), (values[3], values[4], values[5]))

    def to_dict(self) -> dict[str, list[float]]:
        """``{"centre": [x, y, z], "size": [x, y, z]}`` (m): how files and the API store it."""
        return {"centre": list(self.centre), "size": list(self.size)}

    def text(self) -> str:
        """The ``--obstacle`` form of the box."""
        return ",".join(f"{v:g}" for v in (*self.centre, *self.size))


def _three(value: object, what: str) -> list[object]:
    if not isinstance(value, list | tuple) or len(value) != 3:
        raise KinematicsError(
            f"{what} has {value!r} where three numbers belong; give "
            '{"centre": [x, y, z], "size": [x, y, z]} in metres.'
        )
    return list(value)


def _obstacle_numbers(values: list, what: str) -> list[float]:
    """Six finite numbers: a centre within reach and sizes above zero, else one sentence."""
    out = []
    for v in values:
        if not is_real(v):
            raise KinematicsError(
                f"{what} holds {v!r}, not a number; give its centre and sizes in metres."
            )
        out.append(float(v))
    if not all(math.isfinite(v) for v in out):
        raise KinematicsError(
            f"{what} holds NaN or an infinite value; give finite metres for its centre and sizes."
        )
    if any(abs(v) > MAX_OBSTACLE_REACH_M for v in out):
        raise KinematicsError(
            f"{what} lies or reaches beyond {MAX_OBSTACLE_REACH_M:g} m; give a box within the "
            "robot's workspace (metres, not millimetres)."
        )
    if any(v <= 0 for v in out[3:]):
        raise KinematicsError(
            f"{what} has a size of {min(out[3:]):g} m; give each full size above zero."
        )
    return out


def check_obstacles(value: object, what: str = "obstacles") -> tuple[Obstacle, ...]:
    """A list of boxes (:class:`Obstacle`, their dicts or six numbers each) as a tuple.

    Raises:
        KinematicsError: not a list, more than :data:`MAX_OBSTACLES`, or a bad box.
    """
    if value is None:
        return ()
    if not isinstance(value, list | tuple):
        raise KinematicsError(f"{what} is {value!r}; give a list of boxes.")
    if len(value) > MAX_OBSTACLES:
        raise KinematicsError(f"{what} holds {len(value)} boxes; give at most {MAX_OBSTACLES}.")
    return tuple(Obstacle.from_value(v, f"Obstacle {i + 1}") for i, v in enumerate(value))
