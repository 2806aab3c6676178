"""The studio's 3D scene: the mirrored human arm beside the Puma560, drawn with viser.

The live pipeline runs at the tape's 110 Hz; a browser's websocket may be far slower. So
:meth:`StudioScene.update_live` only stores the latest values (latest wins) and a scene thread
pushes them to viser at a bounded rate, one batched message per update. Nothing the pipeline
calls ever waits on a client, and viser coalesces a node's pending updates per client, so a slow
browser skips poses instead of queueing behind them.

World frame: Z up, the Puma560's base on the floor at the origin, facing +X. The operator's arm
is drawn mirrored (as in a mirror held beside the robot, so it moves the way the robot moves) a
little to the robot's side, its shoulder at standing height, with a simple torso and head.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import viser

from studio.kinematics import Puma560


class _ArmPoseLike(Protocol):
    shoulder: np.ndarray
    elbow: np.ndarray
    wrist: np.ndarray
    hand: np.ndarray


class _ArmLike(Protocol):
    nq: int
    neutral: np.ndarray

    def forward(self, q: np.ndarray) -> _ArmPoseLike: ...


@dataclass(frozen=True)
class SceneLayout:
    """Where things stand and how fast the scene is refreshed.

    Attributes:
        human_origin: world position of the human arm's shoulder-base frame (m).
        mirror_axis: axis of the arm frame flipped to draw the arm mirrored (0, 1 or 2), or
            None to draw it as is.
        torso_size: torso box (depth, width, height) in m, hanging below the shoulder.
        rate_hz: most scene pushes per second (latest values win in between).
        floor_half_size: the floor plate reaches this far from its centre (m).
        floor_cell: spacing of the floor's grid lines (m).
        playback_hold_s: how long the robot keeps the last pose of a finished playback before
            following the live pose again.
        camera_position: initial camera position (m).
        camera_look_at: initial camera target (m).
    """

    human_origin: tuple[float, float, float] = (0.0, -0.95, 1.38)
    mirror_axis: int | None = 1
    torso_size: tuple[float, float, float] = (0.22, 0.36, 0.55)
    rate_hz: float = 30.0
    floor_half_size: float = 2.0
    floor_cell: float = 0.25
    playback_hold_s: float = 5.0
    camera_position: tuple[float, float, float] = (1.95, -0.6, 1.6)
    camera_look_at: tuple[float, float, float] = (0.1, -0.42, 0.9)
    colors: dict[str, tuple[int, int, int]] = field(
        default_factory=lambda: {
            "skin": (226, 182, 150),
            "shirt": (70, 110, 160),
            "joint": (60, 60, 66),
            "tape": (20, 190, 120),
            "goal": (230, 60, 60),
            "path": (40, 120, 230),
            "trace": (240, 150, 20),
        }
    )


def _rgb255(rgb: Sequence[float]) -> tuple[int, int, int]:
    return tuple(int(round(255 * min(max(float(c), 0.0), 1.0))) for c in rgb)  # type: ignore[return-value]


def _wxyz(rotations: np.ndarray) -> np.ndarray:
    """Unit quaternions (w, x, y, z) of rotation matrices ``(..., 3, 3)``."""
    r = np.asarray(rotations, dtype=float)
    shape = r.shape[:-2]
    r = r.reshape(-1, 3, 3)
    out = np.empty((r.shape[0], 4))
    for i, m in enumerate(r):
        tr = m[0, 0] + m[1, 1] + m[2, 2]
        if tr > 0:
            s = 2.0 * np.sqrt(tr + 1.0)
            out[i] = (
                0.25 * s,
                (m[2, 1] - m[1, 2]) / s,
                (m[0, 2] - m[2, 0]) / s,
                (m[1, 0] - m[0, 1]) / s,
            )
        elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
            s = 2.0 * np.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
            out[i] = (
                (m[2, 1] - m[1, 2]) / s,
                0.25 * s,
                (m[0, 1] + m[1, 0]) / s,
                (m[0, 2] + m[2, 0]) / s,
            )
        elif m[1, 1] > m[2, 2]:
            s = 2.0 * np.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
            out[i] = (
                (m[0, 2] - m[2, 0]) / s,
                (m[0, 1] + m[1, 0]) / s,
                0.25 * s,
                (m[1, 2] + m[2, 1]) / s,
            )
        else:
            s = 2.0 * np.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
            out[i] = (
                (m[1, 0] - m[0, 1]) / s,
                (m[0, 2] + m[2, 0]) / s,
                (m[1, 2] + m[2, 1]) / s,
                0.25 * s,
            )
    out /= np.linalg.norm(out, axis=1, keepdims=True)
    return out.reshape(*shape, 4)


def _segment_pose(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Centre, orientation (wxyz) and length of a cylinder along z from ``a`` to ``b``."""
    d = b - a
    length = float(np.linalg.norm(d))
    if length < 1e-9:
        return (a + b) / 2, np.array([1.0, 0.0, 0.0, 0.0]), 0.0
    z = d / length
    # Shortest rotation taking +z onto z: axis z0 x z, angle acos(z0 . z).
    w = 1.0 + z[2]
    if w < 1e-9:
        q = np.array([0.0, 1.0, 0.0, 0.0])
    else:
        q = np.array([w, -z[1], z[0], 0.0])
        q /= np.linalg.norm(q)
    return (a + b) / 2, q, length


@dataclass
class _Playback:
    times: np.ndarray
    q: np.ndarray
    tool: np.ndarray
    marks: np.ndarray
    started: float
    shown_until: int = -1


class StudioScene:
    """The studio's viser scene, fed by the live pipeline and by playbacks.

    Args:
        server: the viser server to draw into.
        robot: the Puma560 model (a fresh one by default).
        arm: the human arm model (``HumanArm(side)`` by default); anything with ``forward(q)``
            returning shoulder/elbow/wrist/hand poses and a ``neutral`` pose.
        side: which arm the operator wears the tape on, used when ``arm`` is not given.
        layout: placement, colours and the push rate.
    """

    def __init__(
        self,
        server: viser.ViserServer,
        *,
        robot: Puma560 | None = None,
        arm: _ArmLike | None = None,
        side: str = "right",
        layout: SceneLayout | None = None,
    ) -> None:
        if arm is None:
            from studio.kinematics import HumanArm

            arm = HumanArm(side=side)
        self.server = server
        self.robot = robot if robot is not None else Puma560()
        self.arm = arm
        self.layout = layout if layout is not None else SceneLayout()
        self._side = side
        mirror = np.eye(3)
        if self.layout.mirror_axis is not None:
            mirror[self.layout.mirror_axis, self.layout.mirror_axis] = -1.0
        self._human_R = mirror
        self._human_t = np.asarray(self.layout.human_origin, dtype=float)

        self._lock = threading.Lock()  # guards the fields below
        self._viser_lock = threading.Lock()  # one thread talks to viser at a time
        self._live: tuple[np.ndarray, np.ndarray, np.ndarray | None] | None = None
        self._live_dirty = False
        self._playback: _Playback | None = None
        self._hold_until = 0.0
        self._robot_behind_live = False
        self._q_robot_shown = np.array(self.robot.qz, dtype=float)
        self._q_human_shown = np.asarray(self.arm.neutral, dtype=float).copy()
        self._paths: dict[str, Any] = {}
        self._wake = threading.Event()
        self._closed = threading.Event()
        self.pushes = 0  # scene updates sent, for tests and benchmarks

        self._build()
        self._thread = threading.Thread(target=self._loop, name="studio-scene", daemon=True)
        self._thread.start()

    # ------------------------------------------------------------------ building

    def _build(self) -> None:
        s = self.server.scene
        lay = self.layout
        c = lay.colors
        self.server.gui.configure_theme(
            show_share_button=False, show_logo=False, control_layout="floating"
        )
        self.server.gui.main_panel.minimize()  # the page has the controls; keep the view clear
        cam = self.server.initial_camera
        cam.position = lay.camera_position
        cam.look_at = lay.camera_look_at
        cam.up = (0.0, 0.0, 1.0)
        s.set_up_direction("+z")
        # Plain lights: no shadow maps and no image-based lighting. Both re-render every frame,
        # and in software WebGL (a machine without a GPU) they cost most of a core even while
        # the scene stands still, taken from training; without them the colours also read
        # clearer (the default environment map washed the scene out to near white).
        s.configure_default_lights(enabled=True, cast_shadow=False)
        s.configure_environment_map(hdri=None)
        # A static floor: a plate and line segments. (viser's shader grid and text labels keep
        # the browser redrawing while nothing moves, which costs a core with software WebGL.)
        half, step = lay.floor_half_size, lay.floor_cell
        centre = np.array([0.0, lay.human_origin[1] / 2, 0.0])
        s.add_box(
            "/floor/plate",
            color=(236, 238, 241),
            dimensions=(2 * half, 2 * half, 0.01),
            position=centre - np.array([0.0, 0.0, 0.006]),
            cast_shadow=False,
        )
        ticks = np.arange(-half, half + 1e-9, step)
        lines = [((t, -half, 0.0), (t, half, 0.0)) for t in ticks]
        lines += [((-half, t, 0.0), (half, t, 0.0)) for t in ticks]
        s.add_line_segments(
            "/floor/lines",
            points=np.array(lines) + centre,
            colors=(196, 200, 206),
            thickness=0.004,
        )
        self._robot_handles = self._add_robot("/robot", opacity=None)
        self._ghost_handles = self._add_robot("/goal/ghost", opacity=0.22, visible=False)
        self._goal_marker = s.add_icosphere(
            "/goal/marker", radius=0.035, color=c["goal"], opacity=0.85, visible=False
        )

        # Human: torso, head, shoulder/elbow/wrist spheres, three limb cylinders.
        pose = self.arm.forward(np.asarray(self.arm.neutral, dtype=float))
        pts = self._arm_points(pose)
        self._limb_radius = (0.045, 0.037, 0.028)
        self._limb_lengths = [float(np.linalg.norm(pts[i + 1] - pts[i])) for i in range(3)]
        self._limbs = []
        for i, name in enumerate(("upper_arm", "forearm", "hand")):
            centre, wxyz, _ = _segment_pose(pts[i], pts[i + 1])
            self._limbs.append(
                s.add_cylinder(
                    f"/human/{name}",
                    radius=self._limb_radius[i],
                    height=max(self._limb_lengths[i], 1e-3),
                    color=c["shirt"] if i == 0 else c["skin"],
                    position=centre,
                    wxyz=wxyz,
                )
            )
        self._joints = [
            s.add_icosphere(f"/human/{name}_joint", radius=r, color=c["joint"], position=p)
            for name, r, p in zip(
                ("shoulder", "elbow", "wrist"), (0.05, 0.042, 0.032), pts[:3], strict=True
            )
        ]
        self._add_body(pts[0])
        self._tape = s.add_spline_catmull_rom(
            "/human/tape",
            points=np.stack([pts[0], pts[1]]),
            thickness=0.012,
            color=c["tape"],
            visible=False,
        )
        self._trace_line = s.add_line_segments(
            "/trace/line",
            points=np.zeros((1, 2, 3)),
            colors=c["trace"],
            thickness=0.008,
            visible=False,
        )
        self._trace_marks = s.add_point_cloud(
            "/trace/bins",
            points=np.zeros((1, 3), dtype=np.float32),
            colors=c["trace"],
            point_size=0.035,
            point_shape="circle",
            precision="float32",
            visible=False,
        )
        self._push_robot(self._robot_handles, self._q_robot_shown)

    def _add_robot(self, root: str, opacity: float | None, visible: bool = True) -> list[Any]:
        s = self.server.scene
        poses = self.robot.visual_poses(self.robot.qz)
        handles: list[Any] = []
        for v, pose in zip(self.robot.visuals(), poses, strict=True):
            name = f"{root}/{v.name}"
            color = _rgb255(v.rgb)
            kw: dict[str, Any] = {
                "opacity": opacity,
                "position": pose[:3, 3],
                "wxyz": _wxyz(pose[:3, :3]),
                "visible": visible,
            }
            if opacity is not None:
                kw["cast_shadow"] = False
            if v.shape == "box":
                h = s.add_box(name, color=color, dimensions=tuple(v.dimensions), **kw)
            elif v.shape == "sphere":
                h = s.add_icosphere(name, radius=float(v.dimensions[0]), color=color, **kw)
            else:
                r, length = v.dimensions
                h = s.add_cylinder(name, radius=float(r), height=float(length), color=color, **kw)
            handles.append(h)
        return handles

    def _add_body(self, shoulder: np.ndarray) -> None:
        """A torso hanging below the shoulder on the body's side, a head above it."""
        s = self.server.scene
        c = self.layout.colors
        depth, width, height = self.layout.torso_size
        # In the arm base frame (x forward, y left, z up) the body's midline lies on +y of a
        # right shoulder and on -y of a left one; the drawing mirrors it with the arm.
        side = getattr(self.arm, "side", self._side)
        axis = self._human_R @ np.array([0.0, 1.0 if side == "right" else -1.0, 0.0])
        centre = shoulder + axis * (width / 2 + 0.03) + np.array([0.0, 0.0, -height / 2 + 0.04])
        s.add_box(
            "/human/torso", color=c["shirt"], dimensions=(depth, width, height), position=centre
        )
        s.add_box(
            "/human/hips",
            color=(90, 90, 100),
            dimensions=(depth * 0.95, width * 0.9, centre[2] - height / 2),
            position=(centre[0], centre[1], (centre[2] - height / 2) / 2),
            opacity=0.35,
        )
        s.add_cylinder(
            "/human/neck",
            radius=0.05,
            height=0.1,
            color=c["skin"],
            position=(centre[0], centre[1], centre[2] + height / 2 + 0.04),
        )
        s.add_icosphere(
            "/human/head",
            radius=0.1,
            color=c["skin"],
            position=(centre[0], centre[1], centre[2] + height / 2 + 0.17),
        )

    # ------------------------------------------------------------------ geometry

    def _to_world(self, p: np.ndarray) -> np.ndarray:
        """Arm-frame points ``(..., 3)`` to world points, mirrored and placed."""
        return np.asarray(p, dtype=float) @ self._human_R.T + self._human_t

    def _arm_points(self, pose: _ArmPoseLike) -> np.ndarray:
        local = np.stack(
            [pose.shoulder[:3, 3], pose.elbow[:3, 3], pose.wrist[:3, 3], pose.hand[:3, 3]]
        )
        return self._to_world(local)

    def tool_positions(self, q_robot: np.ndarray) -> np.ndarray:
        """World tool positions of joint configurations ``(N, 6)`` -> ``(N, 3)``."""
        q = np.atleast_2d(np.asarray(q_robot, dtype=float))
        return np.array([self.robot.forward(qi)[:3, 3] for qi in q])

    # ------------------------------------------------------------------ pushing

    def _push_robot(self, handles: list[Any], q_robot: np.ndarray) -> None:
        poses = self.robot.visual_poses(q_robot)
        quats = _wxyz(poses[:, :3, :3])
        for h, pose, wxyz in zip(handles, poses, quats, strict=True):
            h.position = pose[:3, 3]
            h.wxyz = wxyz

    def _push_human(self, q_human: np.ndarray, tape: np.ndarray | None) -> None:
        pts = self._arm_points(self.arm.forward(q_human))
        for i, limb in enumerate(self._limbs):
            centre, wxyz, _ = _segment_pose(pts[i], pts[i + 1])
            limb.position = centre
            limb.wxyz = wxyz
        for joint, p in zip(self._joints, pts[:3], strict=True):
            joint.position = p
        if tape is not None and len(tape) >= 2:
            self._tape.points = self._to_world(tape).astype(np.float32)
            if not self._tape.visible:
                self._tape.visible = True

    def _loop(self) -> None:
        period = 1.0 / self.layout.rate_hz
        last = 0.0
        while not self._closed.is_set():
            self._wake.wait(timeout=period)
            self._wake.clear()
            if self._closed.is_set():
                break
            wait = last + period - time.perf_counter()
            if wait > 0:
                time.sleep(wait)
            last = time.perf_counter()
            try:
                self._tick(last)
            except Exception:  # a client vanishing mid-push must not end the scene thread
                if self._closed.is_set():
                    break

    def _tick(self, now: float) -> None:
        with self._lock:
            live = self._live if self._live_dirty else None
            self._live_dirty = False
            playback = self._playback
            hold = now < self._hold_until
            live_robot = None
            clear_trace = False
            if playback is not None or hold:
                self._robot_behind_live = True
            elif self._robot_behind_live:
                # A playback just ended: go back to the newest live pose even if none is new,
                # and take its trace away with it.
                self._robot_behind_live = False
                clear_trace = True
                if self._live is not None:
                    live_robot = self._live[1]
        q_robot: np.ndarray | None = None
        marks_upto = -1
        finished = False
        if playback is not None:
            t = now - playback.started
            times = playback.times
            if t >= times[-1]:
                q_robot = playback.q[-1]
                k = len(times) - 1
                finished = True
            else:
                k = int(np.searchsorted(times, t, side="right")) - 1
                k = min(max(k, 0), len(times) - 2)
                span = times[k + 1] - times[k]
                w = 0.0 if span <= 0 else (t - times[k]) / span
                q_robot = (1 - w) * playback.q[k] + w * playback.q[k + 1]
            marks_upto = k
        elif live is not None and not hold:
            q_robot = live[1]
        elif live_robot is not None:
            q_robot = live_robot
        if q_robot is None and live is None and playback is None and not clear_trace:
            return
        with self._viser_lock, self.server.atomic():
            if clear_trace:
                self._trace_line.visible = False
                self._trace_marks.visible = False
            if live is not None:
                self._push_human(live[0], live[2])
            if q_robot is not None:
                self._push_robot(self._robot_handles, q_robot)
            if playback is not None and marks_upto > playback.shown_until:
                self._push_trace(playback, marks_upto)
        with self._lock:
            if q_robot is not None:
                self._q_robot_shown = np.array(q_robot, dtype=float)
            if finished and self._playback is playback:
                # Cleared only after the last pose is shown, so `playing` false means "at the end".
                self._playback = None
                self._hold_until = now + self.layout.playback_hold_s
        if live is not None:
            with self._lock:
                self._q_human_shown = np.array(live[0], dtype=float)
        self.pushes += 1

    def _push_trace(self, playback: _Playback, upto: int) -> None:
        playback.shown_until = upto
        tool = playback.tool[: upto + 1]
        if len(tool) >= 2:
            self._trace_line.points = np.stack([tool[:-1], tool[1:]], axis=1).astype(np.float32)
            self._trace_line.visible = True
        marks = playback.marks[playback.marks <= upto]
        if len(marks):
            self._trace_marks.points = playback.tool[marks].astype(np.float32)
            self._trace_marks.visible = True

    # ------------------------------------------------------------------ public API

    def update_live(
        self,
        q_human: np.ndarray,
        q_robot: np.ndarray,
        tape_positions: np.ndarray | None = None,
    ) -> None:
        """Show the latest live pose (never blocks; the scene thread pushes the newest).

        Args:
            q_human: the fitted arm's joints (7,), rad.
            q_robot: the retargeted Puma560 joints (6,), rad.
            tape_positions: the reconstructed tape ``(regions + 1, 3)`` in the arm's frame, m,
                or None to leave the tape as drawn.
        """
        value = (
            np.array(q_human, dtype=float),
            np.array(q_robot, dtype=float),
            None if tape_positions is None else np.array(tape_positions, dtype=float),
        )
        with self._lock:
            self._live = value
            self._live_dirty = True
        self._wake.set()

    def set_goal(self, q_robot_goal: np.ndarray | None) -> None:
        """Show a translucent ghost robot and a marker at the goal (None hides them)."""
        with self._viser_lock, self.server.atomic():
            visible = q_robot_goal is not None
            if visible:
                q = np.asarray(q_robot_goal, dtype=float)
                self._push_robot(self._ghost_handles, q)
                self._goal_marker.position = self.robot.forward(q)[:3, 3]
            for h in self._ghost_handles:
                h.visible = visible
            self._goal_marker.visible = visible

    def show_path(self, name: str, q_robot_path: np.ndarray) -> None:
        """Draw the tool path of a robot joint path ``(N, 6)`` (replaces a path of that name)."""
        tool = self.tool_positions(q_robot_path)
        node = f"/paths/{name}"
        with self._viser_lock, self.server.atomic():
            old = self._paths.pop(name, None)
            if old is not None:
                for h in old:
                    h.remove()
            c = self.layout.colors["path"]
            handles = [
                self.server.scene.add_icosphere(
                    f"{node}/start", radius=0.02, color=(40, 170, 90), position=tool[0]
                ),
                self.server.scene.add_icosphere(
                    f"{node}/end", radius=0.02, color=c, position=tool[-1]
                ),
            ]
            if len(tool) >= 2:
                handles.append(
                    self.server.scene.add_spline_catmull_rom(
                        f"{node}/line", points=tool.astype(np.float32), thickness=0.01, color=c
                    )
                )
            self._paths[name] = handles

    def clear_path(self, name: str | None = None) -> None:
        """Remove the path called ``name`` (every path when None); unknown names are ignored."""
        with self._viser_lock, self.server.atomic():
            names = list(self._paths) if name is None else [name]
            for n in names:
                for h in self._paths.pop(n, []):
                    h.remove()

    def path_names(self) -> list[str]:
        """Names of the paths drawn now."""
        with self._viser_lock:
            return list(self._paths)

    def play_trajectory(
        self,
        times: np.ndarray,
        q_robot: np.ndarray,
        states: Sequence[int] | None = None,
    ) -> None:
        """Animate the robot along a trajectory in real time, tracing the tool and bins.

        Args:
            times: sample times ``(N,)``, s, non-decreasing.
            q_robot: joints ``(N, 6)``, rad.
            states: the grid states visited, one per sample or one per step (then spread evenly
                over the samples); each is marked as the robot passes it. None marks only the
                start and the end.
        """
        t = np.asarray(times, dtype=float).reshape(-1)
        q = np.asarray(q_robot, dtype=float).reshape(len(t), -1)
        if len(t) == 0:
            return
        if len(t) == 1:
            t = np.array([0.0, 1e-3])
            q = np.repeat(q, 2, axis=0)
        t = t - t[0]
        tool = self.tool_positions(q)
        n = len(t)
        if states is not None and len(states) == n:
            s = np.asarray(states)
            marks = np.flatnonzero(np.r_[True, s[1:] != s[:-1]])
        elif states is not None and len(states) >= 2:
            marks = np.round(np.linspace(0, n - 1, len(states))).astype(int)
        else:
            marks = np.array([0, n - 1])
        with self._viser_lock, self.server.atomic():
            self._trace_line.visible = False
            self._trace_marks.visible = False
        with self._lock:
            self._playback = _Playback(t, q, tool, marks, time.perf_counter())
            self._hold_until = 0.0
        self._wake.set()

    def stop_playback(self) -> None:
        """Stop a playback; the robot follows the live pose again."""
        with self._lock:
            self._playback = None
            self._hold_until = 0.0
            if self._live is not None:
                self._live_dirty = True
        self._wake.set()

    @property
    def playing(self) -> bool:
        """Whether a playback is running."""
        with self._lock:
            return self._playback is not None

    def current_q_robot(self) -> np.ndarray:
        """The robot joints the scene shows now (rad, (6,))."""
        with self._lock:
            return self._q_robot_shown.copy()

    def current_q_human(self) -> np.ndarray:
        """The arm joints the scene shows now (rad, (7,))."""
        with self._lock:
            return self._q_human_shown.copy()

    def close(self) -> None:
        """Stop the scene thread (the viser server is the caller's to stop)."""
        self._closed.set()
        self._wake.set()
        self._thread.join(timeout=2.0)
