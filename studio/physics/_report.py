"""What a simulated replay found: :class:`SimulationReport` and its :class:`Contact` list.

``studio simulate --json`` prints :meth:`SimulationReport.as_json` (exactly the keys of
:data:`JSON_KEYS`); the human report and the notes an export writes into its file are
:meth:`SimulationReport.sentences`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from studio.kinematics import TABLE

OBSTACLE_PREFIX = "obstacle_"
"""How a contact names an obstacle box: ``obstacle_1``, ``obstacle_2``, ..."""

JSON_KEYS = (
    "completed",
    "max_joint_error_rad",
    "max_tool_error_m",
    "saturated_samples",
    "contacts",
)
"""The keys of ``studio simulate --json``'s object, in order."""


@dataclass(frozen=True)
class Contact:
    """Two links, or a link and the table, that touched during the replay.

    Attributes:
        link_a, link_b: the links (``link_b`` is ``"table"`` for the table the robot stands on,
            ``obstacle_<i>`` for the i-th obstacle box).
        first_sample: the first trajectory sample at which they touched (0-based).
        first_time_s: that sample's time (s).
        samples: how many samples they touched at.
        depth_m: the deepest they went into each other (m, positive).
    """

    link_a: str
    link_b: str
    first_sample: int
    first_time_s: float
    samples: int
    depth_m: float

    @property
    def kind(self) -> str:
        """``"table"``, ``"obstacle"`` (``link_b`` names it: ``obstacle_1``, ...) or ``"self"``."""
        if self.link_b == TABLE:
            return "table"
        return "obstacle" if self.link_b.startswith(OBSTACLE_PREFIX) else "self"

    def as_json(self) -> dict[str, object]:
        return {
            "kind": self.kind,
            "link_a": self.link_a,
            "link_b": self.link_b,
            "first_sample": self.first_sample,
            "first_time_s": round(self.first_time_s, 6),
            "samples": self.samples,
            "depth_m": round(self.depth_m, 6),
        }

    def sentence(self) -> str:
        what = {"table": "the table", "obstacle": self.link_b.replace("_", " ")}.get(
            self.kind, f"link {self.link_b}"
        )
        return (
            f"link {self.link_a} touched {what} at {self.samples} sample(s) from sample "
            f"{self.first_sample} (t = {self.first_time_s:.3f} s), up to "
            f"{self.depth_m * 1000:.1f} mm deep"
        )


@dataclass(frozen=True)
class SimulationReport:
    """A trajectory replayed in MuJoCo on a robot (:func:`~._replay.simulate`).

    Attributes:
        robot: the robot's name.
        completed: the simulation stayed stable and the arm came to rest within
            :data:`~._replay.COMPLETION_M` of the last sample's tool position.
        max_joint_error_rad: the largest joint tracking error at the samples (rad).
        max_tool_error_m: the largest tool position tracking error at the samples (m).
        saturated_samples: how many samples a joint's motor was at its force limit at (or on
            the way to).
        contacts: every link pair (or link and table) that touched, first touch first.
        samples: the trajectory's samples.
        duration_s: its duration (s).
        saturated_joints: the joints that saturated, in joint order.
        first_saturated_sample: the first sample that saturated (None: none did).
        unlimited_joints: the joints whose URDF gives no force limit (simulated unlimited).
        obstacles: how many obstacle boxes stood in the replay (their contacts are among
            ``contacts``).
        times: the samples' times (s, from 0).
        q_simulated: the simulated joints at each sample ``(samples, nq)`` (rad): the motion
            the robot made, to play in a scene (NaN after the simulation went unstable).
    """

    robot: str
    completed: bool
    max_joint_error_rad: float
    max_tool_error_m: float
    saturated_samples: int
    contacts: tuple[Contact, ...]
    samples: int
    duration_s: float
    saturated_joints: tuple[str, ...] = ()
    first_saturated_sample: int | None = None
    unlimited_joints: tuple[str, ...] = ()
    obstacles: int = 0
    times: np.ndarray | None = field(default=None, compare=False, repr=False)
    q_simulated: np.ndarray | None = field(default=None, compare=False, repr=False)

    def as_json(self) -> dict[str, object]:
        """The report as ``studio simulate --json`` prints it: exactly :data:`JSON_KEYS`."""
        return {
            "completed": self.completed,
            "max_joint_error_rad": round(self.max_joint_error_rad, 9),
            "max_tool_error_m": round(self.max_tool_error_m, 9),
            "saturated_samples": self.saturated_samples,
            "contacts": [c.as_json() for c in self.contacts],
        }

    @property
    def clean(self) -> bool:
        """Completed with no saturation and no contact."""
        return self.completed and not self.saturated_samples and not self.contacts

    def sentences(self) -> list[str]:
        """The report in a few sentences, the verdict first."""
        verdict = "completed" if self.completed else "did NOT complete"
        lines = [
            f"physics (MuJoCo, {self.robot}, {self.samples} samples over "
            f"{self.duration_s:.3f} s): {verdict}; largest tracking error "
            f"{self.max_joint_error_rad:.4f} rad at a joint, "
            f"{self.max_tool_error_m * 1000:.1f} mm at the tool",
        ]
        if self.saturated_samples:
            lines.append(
                f"saturation: {self.saturated_samples} sample(s) from sample "
                f"{self.first_saturated_sample} ask more force than the motors of "
                f"{', '.join(self.saturated_joints)} give"
            )
        else:
            lines.append("saturation: none")
        if self.contacts:
            lines += [f"contact: {c.sentence()}" for c in self.contacts]
        else:
            boxes = f"self, table or the {self.obstacles} obstacle box(es)"
            lines.append(f"contacts: none ({boxes if self.obstacles else 'self or table'})")
        if self.unlimited_joints:
            lines.append(
                f"note: the URDF gives {', '.join(self.unlimited_joints)} no force limit; "
                "simulated without one"
            )
        return lines
