"""The studio's 3D scene: the operator and the Puma560 facing each other, drawn with viser.

Both bodies are drawn from real meshes (:mod:`studio.kinematics._meshes`): Gepetto's whole human
from ``human.urdf``, whose taped arm follows the fit, and the Toolbox's Puma560 link meshes on our
DH frames. They face each other as in front of a mirror: with mirrored retargeting the robot
moves as the operator's reflection.

The studio reads one tape, so the other arm rests: it hangs at its neutral pose (a second tape is
not a source here, so no second arm follows anything). The taped arm is the current source's
(``TapeConfig.side``); :meth:`StudioScene.set_side` moves the tape to the other arm when a source
taped there starts, and the tape is drawn along that arm's sleeve.

The live pipeline runs at the tape's 110 Hz; a browser's websocket may be far slower. So
:meth:`StudioScene.show_live` only poses the operator for the newest :class:`LivePose` (once, in
the kinematics package) and stores it (latest wins), and a scene thread pushes it to viser at a
bounded rate, one batched message per update. What the robot shows at a given instant is the
pure function :func:`pose_at` of the inputs and the clock (:mod:`._model`); the operator's part is
:mod:`._operator`, the robot's :mod:`._robot`, the paths' :mod:`._paths`.

World frame: Z up, floor at z = 0, the Puma560's base at the origin facing +X; the operator
stands on the +X side facing -X.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import viser

from studio.kinematics import (
    HumanBody,
    Puma560,
    pose_body,
)

from ._frames import FramePacer
from ._hand_handle import HandHandle
from ._model import Mode, Playback, SceneLayout, playback_time, pose_at, rescheduled
from ._model import camera_projection as camera_projection
from ._obstacles import SceneObstacles
from ._operator import SceneOperator, _placed
from ._paths import ScenePaths
from ._protocols import LivePose
from ._reach import SceneReach
from ._robot import PUMA, SceneRobot
from ._robot_view import RobotViews
from ._views import SceneCamera

log = logging.getLogger(__name__)

STREAM_STOPPED_S = 2.0
"""A live stream with no pose for this long no longer drives the scene (its frames are free)."""

SOFTWARE_WEBGL_NOTICE = "webgl-software-rendering"
"""The id of the notice viser's client raises by itself when WebGL is drawn in software
(``client/src/BrowserWarning.tsx``). The studio's page says the same in its own words, beside the
scene rather than over it, so every browser that connects gets this notice closed."""


def _close_software_webgl_notice(client: viser.ClientHandle) -> None:
    """Close viser's own software-WebGL notice in a browser that just connected.

    The client raises it before it connects, under a fixed id, and viser's message handler
    closes a notification by id (``RemoveNotificationMessage``); viser has no public call for a
    notice the client raised itself, hence the connection's message queue. A browser whose WebGL
    is missing altogether still gets viser's "WebGL unavailable" notice.
    """
    from viser import _messages

    client._websock_connection.queue_message(
        _messages.RemoveNotificationMessage(SOFTWARE_WEBGL_NOTICE)
    )


@dataclass(frozen=True, eq=False)
class _Live:
    """The newest live pose, for the operator of that ``version`` (the scene thread poses the
    operator for it when it shows it)."""

    pose: LivePose
    version: int


class StudioScene(ScenePaths, SceneRobot, SceneOperator, SceneReach):
    """The studio's viser scene, fed by the live pipeline and by playbacks.

    The operator wears one tape: the taped arm follows the fit, the other arm rests (there is no
    second tape to follow). :meth:`set_side` moves the tape to the other arm at run time.

    Args:
        server: the viser server to draw into.
        robot: the Puma560 model (a fresh one by default).
        side: which arm the operator wears the tape on (ignored when ``body`` is given).
        body: the operator's meshes (``HumanBody(side)`` by default); its ``side`` is the taped
            arm.
        layout: placement, camera, colours and the push rate.
        mesh_cache: the folder keeping the drawn robots' simplified meshes (None: none kept).
    """

    def __init__(
        self,
        server: viser.ViserServer,
        *,
        robot: Puma560 | None = None,
        side: str = "right",
        body: HumanBody | None = None,
        layout: SceneLayout | None = None,
        mesh_cache: Path | None = None,
    ) -> None:
        self.server = server
        self.layout = layout if layout is not None else SceneLayout()
        self.robot = robot if robot is not None else Puma560()
        body = body if body is not None else HumanBody(side, self.layout.mesh)
        self._init_operator(body)
        self._init_robot(RobotViews(self.robot, self.layout.mesh, mesh_cache))

        # Inputs, written by any thread under _lock; the loop reads a snapshot.
        self._lock = threading.Lock()
        self._live: _Live | None = None
        self._live_version = 0
        self._live_at = -np.inf  # when the latest live pose came
        self._live_gap = np.inf  # the gap between live poses, smoothed (s)
        self._playback: Playback | None = None
        # Published by the loop (under _lock) for readers.
        self._q_robot_shown = np.array(self.robot.qz, dtype=float)
        self._sample_shown = -1  # the playback sample of the pose pushed last (-1: live)
        self._q_human_shown = np.zeros(7)
        self._side_shown = body.side
        self._shown_playback: Playback | None = None
        self._shown_mode = Mode.LIVE
        self.pushes = 0  # scene updates sent, for tests and benchmarks
        self.errors = 0  # scene updates that raised (each one is logged)
        self._paths: dict[str, list[viser.SceneNodeHandle]] = {}
        self._paths_lock = threading.Lock()
        self._wake = threading.Event()
        self._closed = threading.Event()
        self._viewer = threading.Event()  # a browser connected: the scene's full rate again

        self._build()
        self.frames = FramePacer(server)  # viser's page draws less: a slow stream, a still scene
        self.hand_handle = HandHandle(server)
        self.obstacles = SceneObstacles(server)  # boxes placed for a run, a watched run's
        self.camera = SceneCamera(server, self.layout)  # presets, following the tool
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
        self.set_default_camera()
        s.set_up_direction("+z")
        # Plain lights: no shadow maps and no image-based lighting. Both re-render every frame,
        # and in software WebGL (a machine without a GPU) they cost most of a core even while
        # the scene stands still, taken from training.
        s.configure_default_lights(enabled=True, cast_shadow=False)
        s.configure_environment_map(hdri=None)
        # A sky/ground fill, so that the sides of the bodies turned from the default lights
        # still read (without it the castings and the shirt go black).
        s.add_light_hemisphere(
            "/lights/fill",
            sky_color=(255, 255, 255),
            ground_color=(120, 120, 130),
            intensity=lay.fill_light,
        )
        # A static floor: a plate and line segments (viser's shader grid keeps the browser
        # redrawing while nothing moves, which costs a core with software WebGL).
        half, step = lay.floor_half_size, lay.floor_cell
        centre = np.array([lay.operator_position[0] / 2, lay.operator_position[1] / 2, 0.0])
        s.add_box(
            "/floor/plate",
            color=c["floor"],
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
            colors=c["floor_lines"],
            thickness=0.004,
        )
        self._build_robot()
        self._operator_handles = self._add_operator()
        self._tape = s.add_spline_catmull_rom(
            "/operator/tape",
            points=np.zeros((2, 3)),
            thickness=0.014,
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
        self._build_reach()
        reset = self.server.gui.add_button("Reset view", hint="Frame both bodies again")
        reset.on_click(lambda event: self.reset_view(event.client))
        # viser's control panel floats over the scene by default (its connection status and
        # the button above): dock it to the right edge, folded into a narrow rail, so that it
        # takes a strip beside the scene instead of covering a corner of it.
        self.server.gui.main_panel.dock_right()
        self.server.gui.main_panel.minimize()
        self.server.on_client_connect(_close_software_webgl_notice)
        self.server.on_client_connect(lambda client: self._viewer.set())

    # ------------------------------------------------------------------ geometry

    def robot_mesh_points(self, q_robot: np.ndarray) -> list[np.ndarray]:
        """World vertices of each robot link mesh at ``q_robot`` (for framing and tests)."""
        view = self._view
        poses = view.poses(np.asarray(q_robot, dtype=float))
        return [_placed(p, m) for p, m in zip(view.parts, poses, strict=True)]

    # ------------------------------------------------------------------ pushing

    def _push_trace(self, playback: Playback, upto: int) -> None:
        tool = playback.tool[: upto + 1]
        if len(tool) >= 2:
            self._trace_line.points = np.stack([tool[:-1], tool[1:]], axis=1).astype(np.float32)
            self._trace_line.visible = True
        marks = playback.marks[playback.marks <= upto]
        if len(marks):
            self._trace_marks.points = playback.tool[marks].astype(np.float32)
            self._trace_marks.visible = True

    def _hide_trace(self) -> None:
        self._trace_line.visible = False
        self._trace_marks.visible = False

    def _period(self) -> float:
        """Seconds between pushes: ``rate_hz`` while a browser shows the scene, else
        ``unviewed_rate_hz`` (the state stays current for readers, and viser's copy for the next
        browser to connect)."""
        lay = self.layout
        viewed = bool(self.server.get_clients())
        return 1.0 / (lay.rate_hz if viewed else min(lay.rate_hz, lay.unviewed_rate_hz))

    def _loop(self) -> None:
        shown = _Shown()
        last = 0.0
        last_logged = -np.inf
        while not self._closed.is_set():
            period = self._period()
            self._wake.wait(timeout=period)
            self._wake.clear()
            wait = last + period - time.perf_counter()
            if wait > 0 and not self._viewer.is_set():
                self._viewer.wait(wait)  # a browser connecting ends the wait: it sees now
            self._viewer.clear()
            if self._closed.is_set():
                break
            last = time.perf_counter()
            try:
                self._tick(last, shown)
            except Exception:
                # Never let one bad update end the scene: log it (at most every few seconds,
                # with its traceback) and count it.
                self.errors += 1
                if last - last_logged > 5.0:
                    log.exception(
                        "The scene update failed (%d so far); still running.", self.errors
                    )
                    last_logged = last

    def _tick(self, now: float, shown: _Shown) -> None:
        with self._lock:
            live, version, playback = self._live, self._live_version, self._playback
            operator, slow = self._operator, self._live_gap >= self.layout.slow_live_s
            streaming = now - self._live_at < STREAM_STOPPED_S
            view, self._next_view = self._next_view, None
            drawn, self._next_drawn = self._next_drawn, None
        self.frames.slow(slow and streaming and playback is None)
        if view is not None:
            with self.server.atomic():
                self._draw_robot(view)
                self.obstacles.follow_robot(view.name)  # the form's boxes: the robot drawn's
            shown.q_robot = None
            if drawn is not None:
                drawn()  # the live chain drives it from now on
        if playback is not None and playback.robot != self._view.name:
            playback = None  # another robot's joints: the robot drawn follows the live pose
        if (
            slow
            and now - shown.live_at < 1.0 / self.layout.slow_live_rate_hz
            and playback is None
            and shown.playback is None
            and operator.version == shown.operator_version
        ):
            return  # a slow stream's newer pose waits for its turn (latest wins)
        if live is not None and live.version != operator.version:
            live = None  # posed for the arm taped before a switch
        pose = pose_at(
            now, None if live is None else live.pose.q_robot, playback, self.layout.playback_hold_s
        )
        new_live = live is not None and version != shown.live_version
        operator_changed = operator.version != shown.operator_version
        robot_changed = pose.q_robot is not None and (
            shown.q_robot is None or not np.array_equal(pose.q_robot, shown.q_robot)
        )
        playback_changed = playback is not shown.playback
        trace_grows = pose.trace_upto > shown.trace_upto and playback is not None
        if not (
            new_live
            or operator_changed
            or robot_changed
            or playback_changed
            or trace_grows
            or pose.mode != shown.mode
        ):
            return
        posed = None  # the operator posed for the new live pose: before viser's batch opens
        if new_live and live is not None:
            p = live.pose
            posed = pose_body(operator.body, p.q_human, p.tape, self.layout.tape_lift_m)
        with self.server.atomic():
            if playback_changed or (pose.mode is Mode.LIVE and shown.trace_upto >= 0):
                self._hide_trace()
                shown.trace_upto = -1
            if posed is not None:
                self._push_operator(operator, posed, whole=operator_changed)
            elif operator_changed:
                self._push_operator(operator, operator.rest, whole=True)
            if operator_changed:
                self._place_reach()  # the other shoulder
            if robot_changed and pose.q_robot is not None:
                self._push_robot(self._robot_handles, pose.q_robot)
                if self.camera.following and len(pose.q_robot) == self._view.nq:
                    self.camera.follow(self._view.tool(pose.q_robot))
            if playback is not None and pose.trace_upto > shown.trace_upto:
                self._push_trace(playback, pose.trace_upto)
                shown.trace_upto = pose.trace_upto
        # Send now rather than at viser's next message window (up to 1/60 s later): the pose
        # is what the operator is waiting to see.
        self.server.flush()
        if new_live:
            shown.live_at = now
        shown.live_version = version
        shown.operator_version = operator.version
        shown.playback = playback
        shown.mode = pose.mode
        if pose.q_robot is not None:
            shown.q_robot = np.array(pose.q_robot, dtype=float)
        with self._lock:
            if pose.q_robot is not None:
                self._q_robot_shown = shown.q_robot.copy()
                self._sample_shown = pose.trace_upto
            if operator_changed:
                self._side_shown = operator.body.side
                self._q_human_shown = np.zeros(len(self._q_human_shown))  # the new arm rests
            if new_live and live is not None:
                self._q_human_shown = live.pose.q_human.copy()
            self._shown_playback = playback
            self._shown_mode = pose.mode
        self.pushes += 1

    # ------------------------------------------------------------------ public API

    def show_live(self, pose: LivePose) -> None:
        """Show the latest live pose (never waits for the browser; the scene thread pushes the
        newest).

        The scene thread poses the operator (:func:`studio.kinematics.pose_body`: the meshes and
        the tape on the sleeve) for the poses it shows only, not for each one a 110 Hz source
        gives. A pose without a tape leaves the tape as drawn.
        """
        pose = LivePose(
            np.array(pose.q_human, dtype=float),
            np.array(pose.q_robot, dtype=float),
            None if pose.tape is None else np.array(pose.tape, dtype=float),
        )
        now = time.perf_counter()
        with self._lock:
            self._live = _Live(pose, self._operator.version)
            self._live_version += 1
            gap = min(now - self._live_at, 1.0)  # a pause counts as one slow gap, not more
            smooth = self._live_gap + 0.25 * (gap - self._live_gap)
            self._live_gap, self._live_at = smooth if np.isfinite(smooth) else gap, now
        self._wake.set()

    def update_live(
        self, q_human: np.ndarray, q_robot: np.ndarray, tape_positions: np.ndarray | None = None
    ) -> None:
        """:meth:`show_live` of ``LivePose(q_human, q_robot, tape_positions)``."""
        self.show_live(LivePose(q_human, q_robot, tape_positions))

    def play_trajectory(
        self,
        times: np.ndarray,
        q_robot: np.ndarray,
        states: Sequence[int] | None = None,
        robot: str | None = None,
    ) -> None:
        """Animate the robot along a trajectory in real time, tracing the tool and bins.

        Args:
            times: sample times ``(N,)``, s, non-decreasing.
            q_robot: joints ``(N, nq)``, rad.
            states: the grid states visited, one per sample or one per step (then spread evenly
                over the samples); each is marked as the robot passes it. None marks only the
                start and the end.
            robot: the robot whose joints these are (None: the Puma560's, as a policy's); it
                plays while that robot is drawn, and any other follows the live pose.
        """
        t = np.asarray(times, dtype=float).reshape(-1)
        q = np.asarray(q_robot, dtype=float).reshape(len(t), -1)
        if len(t) == 0:
            return
        if len(t) == 1:
            t = np.array([0.0, 1e-3])
            q = np.repeat(q, 2, axis=0)
        t = t - t[0]
        n = len(t)
        if states is not None and len(states) == n:
            s = np.asarray(states)
            marks = np.flatnonzero(np.r_[True, s[1:] != s[:-1]])
        elif states is not None and len(states) >= 2:
            marks = np.round(np.linspace(0, n - 1, len(states))).astype(int)
        else:
            marks = np.array([0, n - 1])
        name = robot or PUMA
        tool = self.tool_positions(q, name)
        playback = Playback(t, q, tool, marks, time.perf_counter(), robot=name)
        with self._lock:
            self._playback = playback
        self._wake.set()

    def scrub(
        self,
        t: float | None = None,
        speed: float | None = None,
        paused: bool | None = None,
        step: int = 0,
    ) -> tuple[Playback, float] | None:
        """Reschedule the playback now (:func:`._scene_model.rescheduled`); with no change,
        only read it. None when nothing was played.

        Returns:
            The playback in force and its trajectory time now (s).
        """
        now = time.perf_counter()
        with self._lock:
            playback = self._playback
            if playback is None:
                return None
            if t is not None or speed is not None or paused is not None or step:
                playback = rescheduled(playback, now, t=t, speed=speed, paused=paused, step=step)
                self._playback = playback
        self._wake.set()
        return playback, playback_time(playback, now)

    def hold_pose(self, q_robot: np.ndarray, robot: str | None = None) -> None:
        """Show ``robot`` (the Puma560 when None) at ``q_robot`` (rad, its joints) until the
        next playback or stop: a jogged pose, a paused playback of one pose."""
        q = np.repeat(np.asarray(q_robot, dtype=float).reshape(1, -1), 2, axis=0)
        t = np.array([0.0, 1e-3])
        marks = np.zeros(0, dtype=int)
        name = robot or PUMA
        tool = self.tool_positions(q, name)
        playback = Playback(t, q, tool, marks, time.perf_counter(), paused=True, robot=name)
        with self._lock:
            self._playback = playback
        self._wake.set()

    def stop_playback(self) -> None:
        """Stop a playback; the robot follows the live pose again."""
        with self._lock:
            self._playback = None
        self._wake.set()

    @property
    def mode(self) -> Mode:
        """The mode of the pose shown last."""
        with self._lock:
            return self._shown_mode

    @property
    def playing(self) -> bool:
        """Whether a playback runs (true until the scene has shown its last pose)."""
        with self._lock:
            playback = self._playback
            if playback is None or playback.robot != self._view.name:
                return False
            return self._shown_playback is not playback or self._shown_mode is Mode.PLAYBACK

    def current_q_robot(self) -> np.ndarray:
        """The robot joints the scene shows now (rad, (nq,))."""
        return self.shown_robot()[0]

    def shown_robot(self) -> tuple[np.ndarray, int]:
        """The robot joints the scene shows now (rad, (nq,)) and, for a playback, the sample
        they stand at or after (-1 for a live pose), read together: the scene pushes a new pose
        up to a tick after the playback's clock reaches it."""
        with self._lock:
            return self._q_robot_shown.copy(), self._sample_shown

    def current_q_human(self) -> np.ndarray:
        """The arm joints the scene shows now (rad, (7,))."""
        with self._lock:
            return self._q_human_shown.copy()

    def set_default_camera(self) -> None:
        """Make the layout's camera the one new browsers start with."""
        lay = self.layout
        cam = self.server.initial_camera
        cam.position = lay.camera_position
        cam.look_at = lay.camera_look_at
        cam.up = (0.0, 0.0, 1.0)
        cam.fov = float(np.radians(lay.camera_fov_deg))

    def reset_view(self, client: viser.ClientHandle | None = None) -> None:
        """Put a browser's camera (every browser's when None) back on the default view."""
        lay = self.layout
        clients = [client] if client is not None else list(self.server.get_clients().values())
        for c in clients:
            with c.atomic():
                c.camera.up_direction = (0.0, 0.0, 1.0)
                c.camera.fov = float(np.radians(lay.camera_fov_deg))
                c.camera.position = lay.camera_position
                c.camera.look_at = lay.camera_look_at

    def close(self) -> None:
        """Stop the scene thread (the viser server is the caller's to stop)."""
        self._closed.set()
        self._wake.set()
        self._viewer.set()
        self._thread.join(timeout=2.0)
        self.frames.close()


@dataclass
class _Shown:
    """What the scene thread pushed last (its own bookkeeping; no other thread touches it)."""

    live_version: int = 0
    live_at: float = -np.inf
    operator_version: int = 0
    q_robot: np.ndarray | None = None
    playback: Playback | None = None
    mode: Mode = Mode.LIVE
    trace_upto: int = -1
