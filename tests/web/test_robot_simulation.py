"""``/api/robot/simulate/{kind}/{name}``: the physics report an export would state in its file,
before exporting, as ``studio simulate --json`` gives it."""

from __future__ import annotations

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


def test_an_unknown_source_or_robot_is_one_sentence(client: TestClient) -> None:
    missing = client.get("/api/robot/simulate/recording/nope")
    assert missing.status_code == 404 and isinstance(missing.json()["detail"], str)
    robot = client.get("/api/robot/simulate/demonstration/sample-reach-2", params={"robot": "x"})
    assert robot.status_code == 422 and "Unknown robot" in robot.json()["detail"]
