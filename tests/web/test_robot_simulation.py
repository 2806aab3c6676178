"""``/api/robot/simulate/{kind}/{name}``: the physics report an export would state in its file,
before exporting, as ``studio simulate --json`` gives it."""

from __future__ import annotations

import numpy as np
from fastapi.testclient import TestClient

from studio.physics import JSON_KEYS


def test_a_demonstration_is_simulated_on_the_chosen_robot_before_export(
    client: TestClient,
) -> None:
    r = client.get("/api/robot/simulate/demonstration/sample-reach-2", params={"robot": "panda"})
    assert r.status_code == 200, r.text
    report = r.json()
    assert list(report)[: len(JSON_KEYS)] == list(JSON_KEYS)
    assert report["completed"] is True and report["saturated_samples"] == 0
    assert 0 < report["max_tool_error_m"] < 0.01 and report["contacts"] == []
    assert report["sentences"][0].startswith("physics (MuJoCo, panda")
    # the motion the robot made: the simulated joints at each sample, within the report's error
    q = np.array(report["q_simulated"])
    assert q.shape == (len(report["times"]), 7) and len(q) > 10
    export = client.get("/api/robot/export/demonstration/sample-reach-2", params={"robot": "panda"})
    rows = np.loadtxt(
        [line for line in export.text.splitlines() if not line.startswith(("#", "time"))],
        delimiter=",",
    )
    np.testing.assert_allclose(rows[:, 0], report["times"], atol=1e-6)
    assert np.abs(q - rows[:, 1:]).max() <= report["max_joint_error_rad"] + 1e-6  # CSV digits
    assert report["max_joint_error_rad"] > 0  # simulated, not the plan handed back


def test_an_unknown_source_or_robot_is_one_sentence(client: TestClient) -> None:
    missing = client.get("/api/robot/simulate/recording/nope")
    assert missing.status_code == 404 and isinstance(missing.json()["detail"], str)
    robot = client.get("/api/robot/simulate/demonstration/sample-reach-2", params={"robot": "x"})
    assert robot.status_code == 422 and "Unknown robot" in robot.json()["detail"]
