"""A recording retargeted with its IK branches planned (``retarget_path``): it reaches more of its
frames than the live pass, within the same limits, step cap and clearance."""

from __future__ import annotations

import numpy as np

from studio.capture import human_angles, read_any_recording
from studio.kinematics import RetargetConfig, Retargeter, load_robot, retarget_path, tool_reaches
from studio.kinematics._retarget_path import _route, _Track, _walked
from studio.samples import SAMPLES_DIR

STEP = 0.1


def _missed(route: list[tuple[int, int, int]], frames: int) -> int:
    """The frames a route leaves off its tracks: before, between and after its legs."""
    gaps = sum(c - b - 1 for (_, _, b), (_, c, _) in zip(route, route[1:], strict=False))
    return route[0][1] + gaps + frames - 1 - route[-1][2]


def _track(start: int, values: list[float]) -> _Track:
    return _Track(start, np.array(values, dtype=float)[:, None])


def test_the_route_walks_where_the_branches_are_nearest_not_where_the_first_ends():
    # track 0 holds 0 on frames 0-29; track 1 holds 0.3 on frames 10-19, then climbs to 1.0 by
    # frame 27 and stays there to frame 49. Leaving track 0 where it ends (frame 29) means a
    # walk of 10 steps (9 frames missed); leaving it at frame 10 takes 3 (2 missed).
    first = _track(0, [0.0] * 30)
    second = _track(10, [0.3] * 10 + [0.4 + 0.1 * i for i in range(7)] + [1.0] * 23)
    route = _route([first, second], 50, STEP, set())
    assert _missed(route, 50) == 2
    (k, a, b), (j, c, d) = route
    assert (k, a, j, d) == (0, 0, 1, 49) and 10 <= b <= 16 and c == b + 3


def test_the_route_misses_the_fewest_frames_over_any_number_of_walks():
    # track 0 (frames 0-9) at 0; track 1 (frames 5-20) at 0.2; track 2 (frames 5-39) at 0.5.
    # Straight from 0 to 2 misses 4 frames, starting on track 2 misses 5; by way of track 1,
    # two shorter walks miss 1 + 2.
    tracks = [_track(0, [0.0] * 10), _track(5, [0.2] * 16), _track(5, [0.5] * 35)]
    route = _route(tracks, 40, STEP, set())
    assert [leg[0] for leg in route] == [0, 1, 2] and route[-1][2] == 39
    assert _missed(route, 40) == 3
    # without track 1, the one walk
    route = _route([tracks[0], tracks[2]], 40, STEP, set())
    assert [leg[0] for leg in route] == [0, 1] and _missed(route, 40) == 4


def test_the_route_crosses_a_stretch_no_track_reaches_however_long():
    # frames 10-99 reach on no track (out of reach, say): the route still goes on to track 1
    tracks = [_track(0, [0.0] * 10), _track(100, [0.3] * 21)]
    route = _route(tracks, 121, STEP, set())
    assert [leg[0] for leg in route] == [0, 1] and _missed(route, 121) == 90


def test_an_anchored_route_starts_where_the_last_chunk_ended():
    # track 0 is the last chunk's final pose (frame 0 only); track 1 holds 1.0 throughout.
    # Free, the route starts on track 1; anchored, it walks there from track 0 (10 steps).
    tracks = [_track(0, [0.0]), _track(0, [1.0] * 50)]
    assert _route(tracks, 50, STEP, set())[0][0] == 1
    route = _route(tracks, 50, STEP, set(), anchored=True)
    assert route[0] == (0, 0, 0) and route[1][0] == 1 and _missed(route, 50) == 9


def test_a_walk_struck_out_is_not_taken_again():
    first = _track(0, [0.0] * 30)
    second = _track(10, [0.3] * 40)
    route = _route([first, second], 50, STEP, set())
    assert _missed(route, 50) == 2
    banned = {(0, route[0][2], 1)}
    again = _route([first, second], 50, STEP, banned)
    assert again[0][2] != route[0][2] and _missed(again, 50) == 2


def test_the_walk_between_two_legs_is_straight_and_within_the_step():
    first, second = _track(0, [0.0] * 12), _track(10, [0.3] * 40)
    route = [(0, 0, 10), (1, 13, 49)]
    path, clash = _walked([first, second], route, 50, _NeverTouching(), 0.0)
    assert clash is None
    np.testing.assert_allclose(path[10:14, 0], [0.0, 0.1, 0.2, 0.3])
    assert np.abs(np.diff(path[:, 0])).max() <= STEP + 1e-12


class _NeverTouching:
    """A stand-in arm for one-joint paths: its links never touch, nor the table."""

    def contacts(self, q, margin):
        return []


def _sample(n: int) -> np.ndarray:
    recording = read_any_recording(SAMPLES_DIR / f"sample-reach-{n}.tape.csv")
    return human_angles(recording, slice(None))


def _reached(arm, path: np.ndarray, q_human: np.ndarray) -> np.ndarray:
    targets, config = Retargeter(robot=arm.scratch_copy()), RetargetConfig()
    return np.array(
        [
            tool_reaches(arm, q, targets.hand_target(h), config)
            for q, h in zip(path, q_human, strict=True)
        ]
    )


def test_a_planned_ur3_path_reaches_every_frame_the_live_one_walks_through():
    # Live, sample 3 takes the UR3 onto a branch that runs out twice; the walks to another
    # miss 13% of its frames. Planned, it starts on a branch that lasts: none.
    arm, config = load_robot("ur3"), RetargetConfig()
    q_human = _sample(3)
    live = retarget_path(arm, q_human, as_live=True)
    planned = retarget_path(arm, q_human)
    live_reached, planned_reached = (
        _reached(arm, live.q, q_human),
        _reached(arm, planned.q, q_human),
    )
    print(
        f"UR3, sample 3: reached live {live_reached.mean():.1%}, planned {planned_reached.mean():.1%}"
    )
    assert planned_reached.all() and live_reached.mean() < 0.9
    assert np.all((planned.q >= arm.lower) & (planned.q <= arm.upper))
    assert np.abs(np.diff(planned.q, axis=0)).max() <= config.max_joint_step + 1e-9
    assert not any(arm.self_collisions(q, 0.0) for q in planned.q[::3])
    assert not planned.out_of_reach.any()
    targets = Retargeter(robot=arm.scratch_copy())
    error = [
        np.linalg.norm(arm.forward(q)[:3, 3] - targets.hand_target(h)[:3, 3])
        for q, h in zip(planned.q, q_human, strict=True)
    ]
    np.testing.assert_allclose(planned.position_error, error)


def test_live_a_pose_that_would_touch_is_replaced_by_another_branchs_not_held():
    # Sample 2 brings the UR3's hand over its own base: the IK's nearest pose there would bring
    # its links into contact. The robot held its last pose until the hand left, missing 61% of
    # the frames; a branch clear of contact reaches most of them.
    arm = load_robot("ur3")
    q_human = _sample(2)
    retargeter = Retargeter(robot=arm.scratch_copy())
    held = 0
    for h in q_human:
        retargeter.robot_from_human(h)
        held += retargeter.held
    live = retarget_path(arm, q_human, as_live=True)
    reached = _reached(arm, live.q, q_human)
    print(f"UR3, sample 2, live: reached {reached.mean():.1%}, held {held} frames")
    assert reached.mean() >= 0.8 and held <= 60
    assert not any(arm.self_collisions(q, 0.0) for q in live.q)


def test_a_path_the_live_pass_reaches_whole_is_the_live_path():
    t = np.linspace(0.0, 1.0, 40)[:, None]
    q_human = np.zeros((40, 7))
    q_human[:, 0] = 0.3 + 0.6 * t[:, 0]
    q_human[:, 3] = 0.2 + 0.8 * t[:, 0]
    ur5 = load_robot("ur5")
    np.testing.assert_array_equal(
        retarget_path(ur5, q_human).q, retarget_path(ur5, q_human, as_live=True).q
    )


def test_a_long_recording_is_routed_a_chunk_at_a_time_without_a_seam(monkeypatch):
    # Chunks of 100 frames instead of 2,200: each starts from the last one's final pose, so the
    # step cap holds across the seams, and the route still reaches far more than live.
    import studio.kinematics._retarget_path as planner

    monkeypatch.setattr(planner, "CHUNK", 100)
    arm, config = load_robot("ur3"), RetargetConfig()
    q_human = _sample(3)
    planned = retarget_path(arm, q_human)
    assert np.abs(np.diff(planned.q, axis=0)).max() <= config.max_joint_step + 1e-9
    assert np.all((planned.q >= arm.lower) & (planned.q <= arm.upper))
    live = retarget_path(arm, q_human, as_live=True)
    assert planned.reached.mean() >= 0.95 > live.reached.mean()
