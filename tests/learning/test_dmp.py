"""The movement-primitive baseline: it reproduces demonstrations, generalises its ends, and is a
policy file that loads, rolls out, exports and scores like the others."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from studio.capture import load_demonstration
from studio.learning import (
    DmpPolicyFile,
    LearningError,
    PolicyFileError,
    dmp_likeness_card,
    dtw_distance,
    fit_dmp_policy,
    fit_movement_primitive,
    load_any_policy,
    load_dmp_policy,
    policy_summary,
    roll_out_primitive,
    rollout_dmp_policy,
    save_dmp_policy,
)

SAMPLES = sorted((Path(__file__).resolve().parents[2] / "studio" / "samples").glob("*.demo.json"))


def curve(n: int = 201, duration: float = 2.0):
    t = np.linspace(0.0, duration, n)
    u = t / duration
    q = np.column_stack([np.sin(3 * u) * 0.5 + u, u**2, -0.5 * u + 0.2 * np.sin(6 * u)])
    return t, q


def test_a_primitive_reproduces_a_smooth_path_and_ends_at_its_goal():
    t, q = curve()
    primitive = fit_movement_primitive(t, q)
    times, out = roll_out_primitive(primitive, rate_hz=100.0)
    assert dtw_distance(out, q) < 0.005
    np.testing.assert_allclose(out[-1], q[-1], atol=0.01)
    assert times[0] == 0.0 and times[1] == pytest.approx(0.01)


def test_a_primitive_goes_from_any_start_to_any_goal_with_the_demonstrated_shape():
    t, q = curve()
    primitive = fit_movement_primitive(t, q)
    start, goal = q[0] + [0.3, -0.2, 0.1], q[-1] + [-0.4, 0.2, 0.3]
    _, out = roll_out_primitive(primitive, start, goal, rate_hz=100.0)
    np.testing.assert_allclose(out[0], start)
    np.testing.assert_allclose(out[-1], goal, atol=0.01)
    # joint 2 is shaped like the demonstration, stretched to the new amplitude
    shape = (q[:, 1] - q[0, 1]) / (q[-1, 1] - q[0, 1])
    moved = (out[:, 1] - start[1]) / (goal[1] - start[1])
    assert dtw_distance(moved, shape) < 0.02


@pytest.mark.parametrize("path", SAMPLES, ids=lambda p: p.name)
def test_the_primitive_reproduces_each_sample_demonstration(path):
    demo = load_demonstration(path)
    joints = demo.grid["joints"]
    primitive = fit_movement_primitive(demo.times, demo.q_robot)
    rate = (len(demo.times) - 1) / (demo.times[-1] - demo.times[0])
    _, out = roll_out_primitive(primitive, rate_hz=rate)
    assert dtw_distance(out[:, :joints], demo.q_robot[:, :joints]) <= 0.02


def test_bad_demonstrations_get_one_sentence():
    t, q = curve()
    with pytest.raises(LearningError, match="at least 3"):
        fit_movement_primitive(t[:2], q[:2])
    bad = q.copy()
    bad[5, 0] = np.nan
    with pytest.raises(LearningError, match="NaN"):
        fit_movement_primitive(t, bad)
    with pytest.raises(LearningError, match="one row of joint angles per time"):
        fit_movement_primitive(t[:-1], q)
    primitive = fit_movement_primitive(t, q)
    with pytest.raises(LearningError, match="give 3 finite joint angles"):
        roll_out_primitive(primitive, start=[0.0, 0.0])
    with pytest.raises(LearningError, match="positive number"):
        roll_out_primitive(primitive, rate_hz=0.0)


@pytest.fixture(scope="module")
def demo():
    return load_demonstration(SAMPLES[1])


def test_a_dmp_policy_file_round_trips_and_loads_as_any_policy(tmp_path, demo):
    policy = fit_dmp_policy(demo.times, demo.q_robot, learned_joints=3, notes="baseline")
    path = tmp_path / "dmp.policy.npz"
    card = save_dmp_policy(path, policy)
    loaded = load_any_policy(path)
    assert isinstance(loaded, DmpPolicyFile)
    np.testing.assert_array_equal(loaded.primitive.weights, policy.primitive.weights)
    np.testing.assert_array_equal(loaded.demo_q, demo.q_robot)
    assert loaded.learned_joints == 3 and loaded.notes == "baseline"
    times, q, reached = rollout_dmp_policy(loaded)
    assert reached and q.shape == (len(times), 6)
    np.testing.assert_allclose(q[0], demo.q_robot[0])
    again = dmp_likeness_card(loaded)
    assert again.dtw_rad == pytest.approx(card.dtw_rad)
    assert card.dtw_rad <= 0.02  # from the demonstration's own start
    assert card.demonstration.duration_s == pytest.approx(demo.times[-1] - demo.times[0])
    summary = policy_summary(loaded)
    assert summary["task"]["kind"] == "dmp" and summary["joints"] == 6


def test_a_damaged_dmp_policy_file_is_refused_with_one_sentence(tmp_path, demo):
    policy = fit_dmp_policy(demo.times, demo.q_robot)
    path = tmp_path / "dmp.policy.npz"
    save_dmp_policy(path, policy)
    with np.load(path) as f:
        members = {k: f[k] for k in f.files}
    members["weights"] = members["weights"][:, :-1]
    broken = tmp_path / "broken.policy.npz"
    np.savez(broken, **members)
    with pytest.raises(PolicyFileError, match="broken.policy.npz.*export the policy again"):
        load_dmp_policy(broken)
    with pytest.raises(PolicyFileError, match="does not exist"):
        load_dmp_policy(tmp_path / "missing.policy.npz")


def test_fit_dmp_policy_checks_the_arm(demo):
    with pytest.raises(LearningError, match=r"\(N, 6\)"):
        fit_dmp_policy(demo.times, demo.q_robot[:, :3])
    with pytest.raises(LearningError, match="learned_joints"):
        fit_dmp_policy(demo.times, demo.q_robot, learned_joints=7)


def test_studio_export_rolls_a_dmp_out_and_prints_its_likeness_card(tmp_path, demo, capsys):
    from studio.cli import main

    path = tmp_path / "dmp.policy.npz"
    save_dmp_policy(path, fit_dmp_policy(demo.times, demo.q_robot, learned_joints=3))
    out = tmp_path / "dmp.csv"
    assert main(["export", str(path), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "reaches the goal" in printed and "DTW" in printed and "LDLJ" in printed
    rows = np.loadtxt(out, delimiter=",", skiprows=1)
    np.testing.assert_allclose(rows[0, 1:], demo.q_robot[0], atol=1e-6)
    # from another start too, and a grid state is refused in one sentence
    assert main(["export", str(path), "--start-deg=0,30,-80,0,0,0", "--out", str(out)]) == 0
    assert main(["export", str(path), "--start-state", "3", "--out", str(out)]) == 2
    assert "--start-deg" in capsys.readouterr().err


def test_the_page_lists_and_watches_an_uploaded_dmp_policy(tmp_path, demo):
    from fastapi.testclient import TestClient

    from studio.web import create_app
    from tests.web.conftest import make_settings

    path = tmp_path / "dmp.policy.npz"
    save_dmp_policy(path, fit_dmp_policy(demo.times, demo.q_robot))
    with TestClient(create_app(make_settings(tmp_path))) as client:
        files = {"file": ("dmp.policy.npz", path.read_bytes(), "application/octet-stream")}
        r = client.post("/api/policies", files=files)
        assert r.status_code == 201, r.text
        assert r.json()["task"]["kind"] == "dmp"
        watch = client.post("/api/watch", json={"policy": "dmp"})
        assert watch.status_code == 200, watch.text
        q = np.asarray(watch.json()["q_robot"])
        np.testing.assert_allclose(q[0], demo.q_robot[0], atol=1e-5)
        assert watch.json()["reached_goal"] is True
        csv = client.get("/api/watch/trajectory.csv")
        assert csv.status_code == 200 and csv.text.startswith("time,q1")
