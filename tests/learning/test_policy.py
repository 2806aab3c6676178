from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest

from studio.learning import (
    ArmGrid,
    DynaQConfig,
    PolicyFileError,
    greedy_path,
    load_policy,
    rollout,
    run_experiments,
    save_trajectory_csv,
)
from studio.learning.tabular._policy import save_policy


@pytest.fixture(scope="module")
def trained():
    grid = ArmGrid(joints=2, bins=7, goal=(1, 5))
    config = DynaQConfig(planning="full", planning_steps=30, epsilon=1.0)
    result = run_experiments(grid.mdp(), config, 2, 40, seed=0)
    return grid, config, result


def test_round_trip_and_numpy_only_reading(tmp_path, trained) -> None:
    grid, config, result = trained
    path = tmp_path / "arm.policy.npz"
    written = save_policy(
        path, grid, result.q[0], config, result.mean_steps(), experiments=2, notes="hi"
    )
    loaded = load_policy(path)
    assert loaded.grid == grid and loaded.config == config and loaded.notes == "hi"
    assert loaded.q.tobytes() == result.q[0].tobytes()
    np.testing.assert_array_equal(loaded.greedy, np.argmax(result.q[0], axis=1))
    np.testing.assert_array_equal(loaded.mean_steps, result.mean_steps())
    assert loaded.experiments == 2 and loaded.created == written.created
    with np.load(path, allow_pickle=False) as raw:  # the documented numpy-only way
        header = json.loads(str(raw["header"]))
        assert header["format"] == "teach-studio-policy" and header["version"] == 1
        assert header["grid"]["goal"] == [1, 5] and header["goal_state"] == grid.goal_state
        assert header["config"]["planning"] == "full"
        np.testing.assert_array_equal(raw["greedy"], loaded.greedy)


def _rewrite_header(path, change) -> None:
    with np.load(path, allow_pickle=False) as raw:
        arrays = {name: raw[name] for name in raw.files}
    header = json.loads(str(arrays["header"]))
    change(header)
    arrays["header"] = np.array(json.dumps(header))
    np.savez(path, **arrays)


def test_newer_version_and_corrupt_files_fail_clearly(tmp_path, trained) -> None:
    grid, config, result = trained
    path = tmp_path / "arm.policy.npz"
    save_policy(path, grid, result.q[0], config)
    _rewrite_header(path, lambda h: h.update(version=2))
    with pytest.raises(PolicyFileError, match="version 2, newer than this studio's 1; upgrade"):
        load_policy(path)

    save_policy(path, grid, result.q[0], config)
    _rewrite_header(path, lambda h: h["grid"].update(bins=9))
    with pytest.raises(PolicyFileError, match=r"'q' array has shape \(49, 9\) where \(81, 9\)"):
        load_policy(path)

    truncated = tmp_path / "truncated.policy.npz"
    save_policy(path, grid, result.q[0], config)
    truncated.write_bytes(path.read_bytes()[:200])
    with pytest.raises(PolicyFileError, match="truncated.policy.npz is corrupt"):
        load_policy(truncated)

    garbage = tmp_path / "garbage.policy.npz"
    garbage.write_bytes(b"not a zip at all")
    with pytest.raises(PolicyFileError, match="corrupt"):
        load_policy(garbage)

    other = tmp_path / "other.npz"
    np.savez(other, x=np.zeros(3))
    with pytest.raises(PolicyFileError, match="not a Teach Studio policy file"):
        load_policy(other)
    with zipfile.ZipFile(tmp_path / "bad-json.npz", "w") as archive:
        archive.writestr("header.npy", b"\x93NUMPY nonsense")
    with pytest.raises(PolicyFileError):
        load_policy(tmp_path / "bad-json.npz")
    with pytest.raises(PolicyFileError, match="does not exist"):
        load_policy(tmp_path / "missing.policy.npz")


def test_rollout_follows_the_greedy_path_smoothly(tmp_path, trained) -> None:
    grid, config, result = trained
    policy = save_policy(tmp_path / "p.policy.npz", grid, result.q[0], config)
    start = grid.state_of((6, 0))
    path = greedy_path(policy, start)
    assert path[-1] == grid.goal_state and len(path) - 1 == grid.shortest_steps(start)
    hold = np.array([0.0, 0.0, 0.3, -0.2, 0.1, 0.5])
    rate = 40.0
    times, q = rollout(policy, start, rate_hz=rate, seconds_per_step=0.25, hold=hold)
    assert q.shape == (len(times), 6) and len(times) == (len(path) - 1) * 10 + 1
    np.testing.assert_allclose(np.diff(times), 1 / rate)
    np.testing.assert_allclose(q[0, :2], grid.angles_of(start))
    np.testing.assert_allclose(q[-1, :2], grid.angles_of(grid.goal_state))
    np.testing.assert_array_equal(q[:, 2:], np.broadcast_to(hold[2:], (len(times), 4)))
    np.testing.assert_allclose(q[::10, :2], [grid.angles_of(s) for s in path])  # passes each centre
    assert np.abs(np.diff(q[:, :2], axis=0)).max() < grid.bin_width / 4  # no jumps

    csv_path = tmp_path / "rollout.csv"
    save_trajectory_csv(csv_path, times, q)
    assert csv_path.read_text().splitlines()[0] == "time,q1,q2,q3,q4,q5,q6"
    np.testing.assert_allclose(
        np.loadtxt(csv_path, delimiter=",", skiprows=1), np.column_stack([times, q]), atol=1e-8
    )


def test_policy_summary_lists_both_kinds_with_their_task(tmp_path, trained) -> None:
    from studio.learning import ArmReach, TilePolicyFile, policy_summary

    grid, config, result = trained
    tabular = policy_summary(save_policy(tmp_path / "g.policy.npz", grid, result.q[0], config))
    assert tabular["task"] == {"kind": "arm-grid", **grid.to_dict()}
    assert tabular["grid"] == grid.to_dict() and tabular["joints"] == 2
    reach = ArmReach(joints=4)
    coding = reach.features()
    coder = coding.bind(reach.lower, reach.upper)
    tile = TilePolicyFile(coder, np.zeros((coder.size, reach.n_actions)), config, task=reach)
    listed = policy_summary(tile)
    assert listed["task"] == {
        "kind": "arm-reach",
        **reach.to_dict(),
        "tile_coding": coding.to_dict(),
    }
    assert listed["grid"] == {} and listed["joints"] == 4 and listed["planning"] == config.planning
    assert listed["goal_deg"] == pytest.approx(np.degrees(reach.goal[:4]))
    other = TilePolicyFile(coder, tile.weights, config, env_id="MountainCar-v0")
    assert policy_summary(other)["task"] == {"kind": "MountainCar-v0"}
