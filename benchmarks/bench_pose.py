"""Camera and hand-guide kinematics: landmark-fit accuracy, the filter's lag, and hand IK speed.

(a) Accuracy on synthetic landmarks (``landmarks_from_arm``: the studio's own arm forward
    kinematics for a person of 0.31 / 0.25 / 0.17 m limbs, not the model's defaults), judged by
    the elbow flexion angle and the upper-arm and forearm directions in the torso frame, both
    sides, over ``arm_motion`` (a known teaching motion):
    - exact landmarks, one frame at a time. Goals: elbow RMSE <= 2 deg, directions <= 2 deg;
    - noisy (sigma 1 cm x, y; 3 cm z), one frame at a time. Goals: elbow RMSE <= 10, medians <= 7;
    - a 30 Hz stream through ``PoseStreamFitter`` (sigma 3 cm x, y; 8 cm z), world landmarks
      alone and with image landmarks (3 px jitter), as the page sends them. Goals: elbow RMSE
      <= 10, medians <= 8; Puma560 joints 1-3 (joint-mode retargeting) in the same ArmGrid cell
      as with the true arm in >= 90% of frames.
    The same frames recorded and smoothed with the future (``smooth_landmarks``), as a
    demonstration cut from a camera recording is fitted: its share in the same cell.
    The filter's lag: ``lag_s`` as reported, and as measured (the time shift that best aligns the
    noise-free stream's elbow angle with the truth). Where the cell misses come from: how many
    lie within 2 degrees of a bin edge (a true angle that near an edge is missed by any noise).
(b) The same-cell share of the live fit over several noise draws (``--draws``, seeds 0, 1, ...;
    mean +- s.d. and range, as one draw moves it by a few points), world landmarks alone and
    with image landmarks: before (the torso as fast as the arm, no rigid hand: ``BEFORE``, run on
    the same frames), with the torso's shape slow only, and now; the ratio now / before. Beside
    them the cell goal's ceiling *estimate* at this noise (``ceiling_estimate``): an ideal
    estimate of each frame (the truth plus Gaussian noise of the Cramer-Rao bound of the elbow,
    wrist and hand (pinky, index, thumb) points, the wrist's angles unknown, the shoulder, torso
    and limb lengths known exactly), through a joint-space constant-velocity Kalman filter whose
    motion noise is tuned per joint on the very draw it is judged on; and the same smoothed with
    the future (Rauch-Tung-Striebel: not causal, so not available live). Every assumption
    favours it, yet it is an estimate, not a bound: it is one filter's figure on finitely many
    draws, and a fit that reads the landmarks otherwise (a different motion model) may pass it.
(c) Hand-guide IK time per target, ``fit_hand_pose`` against a baseline measured interleaved in
    the same run: Pinocchio's plain CLIK loop (its ``examples/inverse-kinematics.py``: damped
    pseudo-inverse steps from the neutral arm, no limits, no closed-form start). Goal: median
    < 5 ms; the hand within 1 cm of every reachable target.

The machine is shared: absolute times drift, the ratio much less.

Run: ``python benchmarks/bench_pose.py`` (about 15 minutes on a busy 2-core machine;
``--seconds`` sets the stream length, ``--seed`` the noise of (a)'s streams, ``--draws`` and
``--sides right,left`` those of (b)).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np
import pinocchio as pin

from studio.kinematics import (
    BodyShape,
    HumanArm,
    PoseStreamFitter,
    Retargeter,
    StreamConfig,
    arm_motion,
    fit_hand_pose,
    fit_pose_landmarks,
    landmarks_from_arm,
    smooth_landmarks,
)
from studio.learning import ArmGrid

PERSON = {"upper_arm": 0.31, "forearm": 0.25, "hand": 0.17}
RATE_HZ = 30.0
WARM_UP_S = 2.0
CLIK_ITERATIONS = 1000
CLIK_EPS = 1e-4
CLIK_STEP = 1e-1
CLIK_DAMP = 1e-12
IK_TARGET_S = 5e-3
IMAGE_SIZE = (640, 480)
IMAGE_NOISE_PX = 3.0  # MediaPipe's image landmarks jitter by a few pixels on a still person
EDGE_DEG = 2.0  # a true angle this near a bin edge is missed by any noise
CEILING_DENSITIES = (0.05, 0.1, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0)  # rad/s^2/sqrt(Hz), searched


def limb_directions(arm: HumanArm, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    p = arm.points(q)
    u, f = p[1] - p[0], p[2] - p[1]
    return u / np.linalg.norm(u), f / np.linalg.norm(f)


def angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    return math.degrees(math.acos(float(np.clip(a @ b, -1.0, 1.0))))


def errors(arm: HumanArm, q_true: np.ndarray, q_fit: np.ndarray) -> tuple[float, float, float]:
    u, f = limb_directions(arm, q_true)
    uf, ff = limb_directions(arm, q_fit)
    return angle_deg(uf, ff) - angle_deg(u, f), angle_deg(u, uf), angle_deg(f, ff)


def noisy(world: np.ndarray, rng: np.random.Generator, xy: float, z: float) -> np.ndarray:
    out = world.copy()
    out[:, :2] += rng.normal(0.0, xy, (len(out), 2))
    out[:, 2] += rng.normal(0.0, z, len(out))
    return out


def summary(rows: list[tuple[float, float, float]]) -> tuple[float, float, float, float, float]:
    e = np.asarray(rows)
    rmse = math.sqrt(float(np.mean(e[:, 0] ** 2)))
    return rmse, float(np.median(e[:, 1])), float(np.median(e[:, 2])), e[:, 1].max(), e[:, 2].max()


def single_frames(arm: HumanArm, seconds: float, noise: tuple[float, float], seed: int) -> list:
    rng = np.random.default_rng(seed)
    rows = []
    for t in np.arange(0.0, seconds, 3.0 / RATE_HZ):
        q = arm_motion(t, arm)
        world = noisy(landmarks_from_arm(q, arm)[0], rng, *noise)
        rows.append(errors(arm, q, fit_pose_landmarks(world, arm.side).q_human))
    return rows


def noisy_image(image: np.ndarray, rng: np.random.Generator, pixels: float) -> np.ndarray:
    """Normalised image landmarks with ``pixels`` of jitter (s.d.) in a 640 x 480 picture."""
    out = image.copy()
    out[:, :2] += rng.normal(0.0, pixels, (len(out), 2)) / np.array(IMAGE_SIZE)
    return out


def stream(
    arm: HumanArm,
    seconds: float,
    noise: tuple[float, float],
    seed: int,
    image_px: float | None = None,
):
    """(error rows, fraction of frames in the same Puma cell, true and fitted elbow angles, lag,
    fraction of frames each of Puma joints 1-3 leaves the true arm's bin, fraction of those
    misses whose true angle lies within ``EDGE_DEG`` of its bin's edge).

    With ``image_px``, each frame also gives image landmarks with that jitter, as the page sends
    both.
    """
    fitter = PoseStreamFitter(arm.side)
    retarget = Retargeter("joint", arm=HumanArm(arm.side))
    grid = ArmGrid()
    rows, same, elbows, off, near = [], [], [], [], []
    for t, q, world, image in zip(*noisy_frames(arm, seconds, noise, seed, image_px), strict=True):
        if image is None:
            fit = fitter.update(float(t), world)
        else:
            fit = fitter.update(float(t), world, image, image_size=IMAGE_SIZE)
        if t < WARM_UP_S:
            continue
        rows.append(errors(arm, q, fit.q_human))
        true_angles = retarget.robot_from_human(q)[:3]
        cells = [
            grid.bins_of_angles(x)
            for x in (true_angles, retarget.robot_from_human(fit.q_human)[:3])
        ]
        same.append(bool(np.array_equal(*cells)))
        off.append(cells[0] != cells[1])
        near.extend(edge_distance_deg(grid, true_angles)[off[-1]] <= EDGE_DEG)
        elbows.append((q[3], fit.q_human[3]))
    near_edge = float(np.mean(near)) if near else 0.0
    return (
        rows,
        float(np.mean(same)),
        np.asarray(elbows),
        fitter.lag_s,
        np.mean(off, axis=0),
        near_edge,
    )


def noisy_frames(
    arm: HumanArm, seconds: float, noise: tuple[float, float], seed: int, image_px: float | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray, list]:
    """Times, true arms, noisy world landmarks and (with ``image_px``) noisy image landmarks of
    ``arm_motion`` at 30 Hz (None per frame without)."""
    rng = np.random.default_rng(seed)
    times = np.arange(0.0, seconds, 1.0 / RATE_HZ)
    truth, worlds, images = [], [], []
    for t in times:
        q = arm_motion(t, arm)
        world, image = landmarks_from_arm(q, arm)
        truth.append(q)
        worlds.append(noisy(world, rng, *noise))
        images.append(None if image_px is None else noisy_image(image, rng, image_px))
    return times, np.array(truth), np.array(worlds), images


def recorded_same_cell(
    arm: HumanArm, seconds: float, noise: tuple[float, float], seed: int, image_px: float | None
) -> float:
    """The same stream as :func:`stream` (the same noise) recorded, then smoothed with the future
    (``smooth_landmarks``) and fitted, as a demonstration cut from a camera recording is: the
    share of frames after the warm-up whose Puma cell is the true arm's."""
    times, truth, worlds, images = noisy_frames(arm, seconds, noise, seed, image_px)
    image = None if image_px is None else np.array(images)
    worlds, image = smooth_landmarks(times, worlds, image, IMAGE_SIZE if image_px else None)
    fitter = PoseStreamFitter(arm.side)
    retarget, grid = Retargeter("joint", arm=HumanArm(arm.side)), ArmGrid()
    same = []
    for k, t in enumerate(times):
        size = None if image is None else IMAGE_SIZE
        frame_image = None if image is None else image[k]
        fit = fitter.update(float(t), worlds[k], frame_image, size, smoothed=True)
        if t >= WARM_UP_S:
            cells = [
                grid.bins_of_angles(retarget.robot_from_human(x)[:3])
                for x in (truth[k], fit.q_human)
            ]
            same.append(bool(np.array_equal(*cells)))
    return float(np.mean(same))


def edge_distance_deg(grid: ArmGrid, angles: np.ndarray) -> np.ndarray:
    """Per angle (rad), the distance (deg) to the nearest edge of its ArmGrid bin."""
    inside = np.mod(angles - math.radians(grid.low_deg), grid.bin_width)
    return np.degrees(np.minimum(inside, grid.bin_width - inside))


CEILING_POINTS = {"right": [14, 16, 18, 20, 22], "left": [13, 15, 17, 19, 21]}
"""BlazePose indices of the points the ceiling estimate measures, per side: elbow, wrist and the
hand's pinky, index and thumb (the shoulder is taken as known)."""


def frame_jacobian(arm: HumanArm, q: np.ndarray) -> np.ndarray:
    """d(elbow, wrist and hand points) / d(the seven angles) at ``q``: (15, 7), m per rad, in
    MediaPipe's world axes (x, y across the picture, z depth), the points as
    ``landmarks_from_arm`` draws them."""
    rows, step = CEILING_POINTS[arm.side], 1e-6
    jac = np.zeros((3 * len(rows), arm.nq))
    for i in range(arm.nq):
        dq = np.zeros(arm.nq)
        dq[i] = step
        ahead, back = (landmarks_from_arm(q + s * dq, arm)[0][rows, :3] for s in (1.0, -1.0))
        jac[:, i] = (ahead - back).reshape(-1) / (2 * step)
    return jac


def frame_covariance(jac: np.ndarray, xy_m: float, depth_m: float) -> np.ndarray:
    """The Cramer-Rao bound (4 x 4, rad^2) of the shoulder and elbow angles from one frame.

    From the elbow, wrist and hand points (``jac`` from :func:`frame_jacobian`), measured with
    s.d. ``xy_m`` across the picture and ``depth_m`` in depth, the shoulder fixed: the least any
    unbiased estimate of that frame can reach, the wrist's three angles unknown (marginalised).
    """
    weights = np.tile([xy_m**-2, xy_m**-2, depth_m**-2], len(jac) // 3)
    fisher = jac.T @ (weights[:, None] * jac) + 1e-12 * np.eye(jac.shape[1])
    return np.linalg.inv(fisher)[:4, :4]


def kalman_angles(measured: list, covs: list, densities: list, smooth: bool) -> np.ndarray:
    """A joint-space constant-velocity Kalman filter (motion noise ``densities`` per joint,
    rad/s^2/sqrt(Hz)) of ``measured`` angles with covariances ``covs``; RTS-smoothed on
    ``smooth``. Returns the filtered angles, (frames, 4)."""
    dt, eye = 1.0 / RATE_HZ, np.eye(4)
    F = np.block([[eye, dt * eye], [0 * eye, eye]])
    a2 = np.diag(np.asarray(densities) ** 2)
    Q = np.block([[a2 * dt**3 / 3, a2 * dt**2 / 2], [a2 * dt**2 / 2, a2 * dt]])
    x, P = np.r_[measured[0], np.zeros(4)], np.block([[covs[0], 0 * eye], [0 * eye, eye]])
    filtered, predicted = [], []
    for z, R in zip(measured, covs, strict=True):
        if filtered:
            x, P = F @ x, F @ P @ F.T + Q
        predicted.append((x, P))
        K = P[:, :4] @ np.linalg.inv(P[:4, :4] + R)
        x, P = x + K @ (z - x[:4]), P - K @ P[:4, :]
        filtered.append((x, P))
    if smooth:
        for k in range(len(filtered) - 2, -1, -1):
            (xf, Pf), (xp, Pp), (xs, Ps) = filtered[k], predicted[k + 1], filtered[k + 1]
            A = Pf @ F.T @ np.linalg.inv(Pp)
            filtered[k] = (xf + A @ (xs - xp), Pf + A @ (Ps - Pp) @ A.T)
    return np.array([x[:4] for x, _ in filtered])


def ceiling_estimate(
    arm: HumanArm, seconds: float, seeds: list[int], noises: list[tuple[float, float]]
) -> list[list[tuple[float, float]]]:
    """Per (xy, depth) noise (m), per seed (one noise draw each): the same-cell fraction of the
    ideal causal filter and of the same smoothed with the future.

    See the module docstring: every frame measured at its Cramer-Rao bound from the elbow,
    wrist and hand points, the motion noise searched per joint over ``CEILING_DENSITIES`` for the
    best causal figure on each draw.
    """
    truth = arm_motion(np.arange(0.0, seconds, 1.0 / RATE_HZ), arm)
    jacobians = [frame_jacobian(arm, q) for q in truth]
    retarget, grid = Retargeter("joint", arm=HumanArm(arm.side)), ArmGrid()
    start = int(WARM_UP_S * RATE_HZ)
    true_cells = grid.bins_of_angles([retarget.robot_from_human(q)[:3] for q in truth[start:]])

    def same_cell(angles: np.ndarray) -> float:
        fitted = truth[start:].copy()
        fitted[:, :4] = angles[start:]
        robot = [retarget.robot_from_human(q)[:3] for q in fitted]
        return float(np.mean(np.all(grid.bins_of_angles(robot) == true_cells, axis=1)))

    out = []
    for xy_m, depth_m in noises:
        covs = [frame_covariance(jac, xy_m, depth_m) for jac in jacobians]
        roots = [np.linalg.cholesky(c) for c in covs]
        draws = []
        for seed in seeds:
            rng = np.random.default_rng(seed)
            measured = [q[:4] + r @ rng.normal(size=4) for q, r in zip(truth, roots, strict=True)]
            densities = [0.5] * 4
            for joint in range(4):
                scores = []
                for value in CEILING_DENSITIES:
                    trial = densities[:joint] + [value] + densities[joint + 1 :]
                    scores.append((same_cell(kalman_angles(measured, covs, trial, False)), value))
                densities[joint] = max(scores)[1]
            causal = same_cell(kalman_angles(measured, covs, densities, False))
            smoothed = same_cell(kalman_angles(measured, covs, densities, True))
            draws.append((causal, smoothed))
        out.append(draws)
    return out


def delayed_same_cell(arm: HumanArm, seconds: float, lag_s: float) -> float:
    """Fraction of frames whose Puma cell is the true arm's when the arm is ``lag_s`` late.

    The ceiling a fit exact but for that lag reaches: the cell goal's lag budget.
    """
    retarget = Retargeter("joint", arm=HumanArm(arm.side))
    grid = ArmGrid()
    t = np.arange(WARM_UP_S, seconds, 1.0 / RATE_HZ)
    same = [
        np.array_equal(*(grid.bins_of_angles(retarget.robot_from_human(x)[:3]) for x in pair))
        for pair in zip(arm_motion(t, arm), arm_motion(t - lag_s, arm), strict=True)
    ]
    return float(np.mean(same))


def measured_lag_s(elbows: np.ndarray) -> float:
    """The delay (s) that best aligns the fitted elbow angle with the true one."""
    true, fitted = elbows[:, 0], elbows[:, 1]
    shifts = range(0, int(RATE_HZ))
    cost = [np.mean((fitted[k:] - true[: len(true) - k]) ** 2) for k in shifts]
    return int(np.argmin(cost)) / RATE_HZ


def image_metres(pixels: float) -> float:
    """``pixels`` of image jitter in metres at the person (the synthetic camera's distance)."""
    body = BodyShape()
    focal = body.image_size[0] / 2 / math.tan(body.camera_fov / 2)
    return pixels * body.camera_distance / focal


def print_cells(side: str, off: np.ndarray, near_edge: float) -> None:
    print(
        f"  {side:5s} frames off the true bin, Puma joint 1 / 2 / 3: "
        + " / ".join(f"{100 * v:.1f}%" for v in off)
        + f"; {100 * near_edge:.0f}% of these misses within {EDGE_DEG:.0f} deg of a bin edge"
    )


def print_recorded(side: str, same: float) -> None:
    print(
        f"  {side:5s} the same frames recorded, smoothed with the future (a demonstration cut "
        f"from them): same cell {100 * same:.1f}%"
    )


BEFORE = StreamConfig(torso_acceleration=StreamConfig().acceleration, rigid_hand=False)
"""The live fit as it was before the torso's shape was filtered slowly and the hand pinned the
wrist: the baseline of :func:`draws`, run on the same frames."""


def cell_shares(
    arm: HumanArm,
    seconds: float,
    seed: int,
    image_px: float | None,
    configs: list[StreamConfig],
    noise: tuple[float, float] = (0.03, 0.08),
) -> list[float]:
    """Per stream config, the share of frames after the warm-up whose Puma cell is the true
    arm's, every config fed the same noisy frames (``noise``: sigma x, y and depth, m)."""
    fitters = [PoseStreamFitter(arm.side, config) for config in configs]
    retarget, grid = Retargeter("joint", arm=HumanArm(arm.side)), ArmGrid()
    same: list[list[bool]] = [[] for _ in configs]
    for t, q, world, image in zip(*noisy_frames(arm, seconds, noise, seed, image_px), strict=True):
        size = None if image is None else IMAGE_SIZE
        fits = [fitter.update(float(t), world, image, size) for fitter in fitters]
        if t < WARM_UP_S:
            continue
        true_cell = grid.bins_of_angles(retarget.robot_from_human(q)[:3])
        for shares, fit in zip(same, fits, strict=True):
            cell = grid.bins_of_angles(retarget.robot_from_human(fit.q_human)[:3])
            shares.append(bool(np.array_equal(true_cell, cell)))
    return [float(np.mean(shares)) for shares in same]


def spread(values: list[float]) -> str:
    """``mean +- s.d. (min-max)`` of shares, in percent."""
    v = 100 * np.asarray(values)
    return f"{v.mean():.1f} +- {v.std(ddof=1):.1f}% ({v.min():.1f}-{v.max():.1f})"


def draws(seconds: float, seeds: list[int], sides: list[str]) -> None:
    """The live fit, before and now, against the ceiling estimate, over several noise draws."""
    world_xy = 0.03
    image_xy = image_metres(IMAGE_NOISE_PX)
    both_xy = (world_xy**-2 + image_xy**-2) ** -0.5  # an ideal fit weighs the two together
    print(
        f"(b) Puma joints 1-3 in the true arm's cell, live, over {len(seeds)} noise draws "
        f"(seeds {seeds[0]}-{seeds[-1]}; mean +- s.d. (range)):"
    )
    for side in sides:
        arm = HumanArm(side, **PERSON)
        ceilings = ceiling_estimate(arm, seconds, seeds, [(world_xy, 0.08), (both_xy, 0.08)])
        for image_px, ceiling in zip((None, IMAGE_NOISE_PX), ceilings, strict=True):
            label = "3/8 cm" if image_px is None else f"3/8 cm + image {image_px:.0f} px"
            configs = [BEFORE, StreamConfig(rigid_hand=False), StreamConfig()]
            shares = [cell_shares(arm, seconds, seed, image_px, configs) for seed in seeds]
            before, torso, now = ([row[k] for row in shares] for k in range(3))
            causal, smoothed = ([row[k] for row in ceiling] for k in (0, 1))
            print(f"  {side:5s} {label}:")
            print(f"        before (torso as fast as the arm, no rigid hand): {spread(before)}")
            print(f"        the torso's shape slow only: {spread(torso)}")
            print(f"        now (torso's shape slow, the rigid hand pins the wrist): {spread(now)}")
            print(
                f"        ratio now / before {np.mean(now) / np.mean(before):.3f}x, "
                f"{100 * (np.mean(now) - np.mean(before)):+.1f} points"
            )
            print(
                f"        ceiling estimate (ideal causal filter, shoulder known, elbow, wrist and "
                f"hand points at their Cramer-Rao bound): {spread(causal)}; smoothed with the "
                f"future {spread(smoothed)}; now / estimate {np.mean(now) / np.mean(causal):.3f}x"
            )


def accuracy(seconds: float, seed: int) -> None:
    print("(a) landmark fit accuracy (deg): elbow RMSE, median upper / forearm direction error")
    for side in ("right", "left"):
        arm = HumanArm(side, **PERSON)
        exact = summary(single_frames(arm, seconds, (0.0, 0.0), 0))
        print(
            f"  {side:5s} exact, one frame:      elbow {exact[0]:.2g}, max directions "
            f"{exact[3]:.2g} / {exact[4]:.2g}   (goal <= 2, <= 2)"
        )
        single = summary(single_frames(arm, seconds, (0.01, 0.03), 1))
        print(
            f"  {side:5s} noisy 1/3 cm, one frame: elbow {single[0]:.2f}, medians "
            f"{single[1]:.2f} / {single[2]:.2f}   (goal <= 10, <= 7)"
        )
        rows, same, _, lag, off, near_edge = stream(arm, seconds, (0.03, 0.08), seed)
        streamed = summary(rows)
        print(
            f"  {side:5s} 30 Hz stream 3/8 cm:     elbow {streamed[0]:.2f}, medians "
            f"{streamed[1]:.2f} / {streamed[2]:.2f}   (goal <= 10, <= 8); Puma joints 1-3 in the "
            f"same cell {100 * same:.1f}% of frames (goal >= 90%)"
        )
        print_cells(side, off, near_edge)
        print_recorded(side, recorded_same_cell(arm, seconds, (0.03, 0.08), seed, None))
        rows, same, _, _, off, near_edge = stream(arm, seconds, (0.03, 0.08), seed, IMAGE_NOISE_PX)
        streamed = summary(rows)
        print(
            f"  {side:5s} 30 Hz stream 3/8 cm + image {IMAGE_NOISE_PX:.0f} px: elbow "
            f"{streamed[0]:.2f}, medians {streamed[1]:.2f} / {streamed[2]:.2f}   (goal <= 10, <= 8);"
            f" Puma joints 1-3 in the same cell {100 * same:.1f}% of frames (goal >= 90%)"
        )
        print_cells(side, off, near_edge)
        print_recorded(side, recorded_same_cell(arm, seconds, (0.03, 0.08), seed, IMAGE_NOISE_PX))
        _, same_clean, elbows, _, _, _ = stream(arm, seconds, (0.0, 0.0), 3)
        print(
            f"  {side:5s} filter lag: reported {lag:.3f} s, measured on the noise-free stream "
            f"{measured_lag_s(elbows):.3f} s; same cell without noise {100 * same_clean:.1f}%"
        )
        ceiling = {lag: delayed_same_cell(arm, seconds, lag) for lag in (0.033, 0.1)}
        print(
            f"  {side:5s} same cell for the true arm only delayed: "
            + ", ".join(f"{1e3 * lag:.0f} ms {100 * v:.1f}%" for lag, v in ceiling.items())
        )


def clik(arm: HumanArm, data: pin.Data, oMdes: pin.SE3) -> tuple[np.ndarray, float]:
    """Pinocchio's example CLIK loop (no limits) from the neutral arm: (q, position error)."""
    model, frame = arm.model, arm.hand_frame
    q = pin.neutral(model)
    for _ in range(CLIK_ITERATIONS):
        pin.framesForwardKinematics(model, data, q)
        iMd = data.oMf[frame].actInv(oMdes)
        err = pin.log(iMd).vector
        if np.linalg.norm(err) < CLIK_EPS:
            break
        J = pin.computeFrameJacobian(model, data, q, frame)
        J = -np.dot(pin.Jlog6(iMd.inverse()), J)
        v = -J.T.dot(np.linalg.solve(J.dot(J.T) + CLIK_DAMP * np.eye(6), err))
        q = pin.integrate(model, q, v * CLIK_STEP)
    pin.framesForwardKinematics(model, data, q)
    return q, float(np.linalg.norm(data.oMf[frame].translation - oMdes.translation))


def ik_speed(targets: int) -> None:
    arm = HumanArm("right")
    data = arm.model.createData()
    rng = np.random.default_rng(5)
    ours, base, ours_err, base_err, within = [], [], [], [], []
    for q in rng.uniform(arm.lower, arm.upper, size=(targets, arm.nq)):
        oMhand = arm.forward(q).hand
        t0 = time.perf_counter()
        fit = fit_hand_pose(oMhand, "right")
        t1 = time.perf_counter()
        q_clik, err = clik(arm, data, pin.SE3(oMhand))
        t2 = time.perf_counter()
        ours.append(t1 - t0)
        base.append(t2 - t1)
        ours_err.append(fit.position_error_m)
        base_err.append(err)
        within.append(bool(np.all(q_clik >= arm.lower) and np.all(q_clik <= arm.upper)))
    med_ours, med_base = float(np.median(ours)), float(np.median(base))
    print(f"(c) hand IK, {targets} random reachable targets (cold start), interleaved:")
    print(
        f"  fit_hand_pose: median {1e3 * med_ours:.2f} ms, p90 {1e3 * np.percentile(ours, 90):.2f}"
        f" ms, within 1 cm {100 * np.mean(np.array(ours_err) <= 0.01):.1f}%, within limits 100%"
        f"   (goal median < {1e3 * IK_TARGET_S:.0f} ms)"
    )
    print(
        f"  Pinocchio CLIK: median {1e3 * med_base:.2f} ms, p90 {1e3 * np.percentile(base, 90):.2f}"
        f" ms, within 1 cm {100 * np.mean(np.array(base_err) <= 0.01):.1f}%, within limits "
        f"{100 * np.mean(within):.1f}%"
    )
    print(f"  ratio (CLIK / ours, median): {med_base / med_ours:.1f}x")
    warm, q_prev = [], None
    drag = arm_motion(np.arange(0.0, 10.0, 1.0 / 60.0), arm)  # a hand dragged at 60 Hz
    for q in drag:
        t0 = time.perf_counter()
        q_prev = fit_hand_pose(arm.forward(q).hand, "right", q_seed=q_prev).q_human
        warm.append(time.perf_counter() - t0)
    print(f"  fit_hand_pose while dragging (seeded): median {1e3 * np.median(warm):.2f} ms")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=30.0, help="motion length per case")
    parser.add_argument("--targets", type=int, default=200, help="IK targets")
    parser.add_argument("--seed", type=int, default=2, help="the noisy streams' noise seed")
    parser.add_argument(
        "--draws", type=int, default=5, help="noise draws of the before/now/ceiling figures"
    )
    parser.add_argument(
        "--sides", default="right", help="arms of the before/now/ceiling figures: right,left"
    )
    args = parser.parse_args()
    accuracy(args.seconds, args.seed)
    draws(args.seconds, list(range(args.draws)), args.sides.split(","))
    ik_speed(args.targets)


if __name__ == "__main__":
    main()
