"""The web layer's services: each route asks for the one it acts on, a test can replace it, and a
run form becomes the learning package's request by its own method."""

from __future__ import annotations

import numpy as np
import pytest
from pydantic import TypeAdapter

from studio.learning import DemonstrationPath, RunRequest, resolve_run
from studio.web._deps import get_policies, get_robots
from studio.web._schemas import RunCreate

RUN_CREATE: TypeAdapter[RunCreate] = TypeAdapter(RunCreate)


class FixedRobots:
    """A robots service that always offers one made-up robot."""

    def public(self) -> dict[str, object]:
        return {
            "robots": [{"name": "toy", "title": "Toy", "joints": ["a", "b", "c"], "goal_deg": []}],
            "robot": "toy",
            "drawn": None,
            "drawn_meshes": 0,
            "limit_margin_rad": 0.02,
        }


def test_a_route_uses_the_service_a_test_puts_in_its_place(client):
    client.app.dependency_overrides[get_robots] = FixedRobots
    try:
        answer = client.get("/api/robots")
    finally:
        del client.app.dependency_overrides[get_robots]
    assert answer.status_code == 200
    assert answer.json()["robot"] == "toy"
    assert [r["name"] for r in answer.json()["robots"]] == ["toy"]
    assert client.get("/api/robots").json()["robot"] == "puma560"  # the studio's own again


def test_the_policy_list_is_the_policies_services(client):
    class NoPolicies:
        def listed(self) -> list:
            return []

    assert client.get("/api/policies").status_code == 200
    client.app.dependency_overrides[get_policies] = NoPolicies
    try:
        assert client.get("/api/policies").json() == []
    finally:
        del client.app.dependency_overrides[get_policies]


@pytest.mark.parametrize(
    "form",
    [
        {},
        {"planning": "prioritized", "planning_steps": 7, "alpha": 0.3, "bins": 12, "seed": 4},
        {"name": "mine", "robot": "ur5", "goal_deg": [10, -20, 30], "episodes": 9},
        {"task": "arm-reach", "joints": 4, "step_deg": 1.5, "actions": "pairs", "tilings": 4},
        {"task": "arm-reach", "tiles": 16, "bins": 9, "experiments": 3, "epsilon": 0.2},
    ],
)
def test_a_run_form_becomes_the_request_its_fields_say(form):
    """Every field the page sets reaches the request, by name, and the learning package checks
    the same run the page's form describes (its record's form holds the same values)."""
    create = RUN_CREATE.validate_python(form)
    demo = DemonstrationPath("Demonstration 'd'", np.zeros((3, 6)), name="d")
    request = create.request(create.robot or "puma560", [demo])
    assert isinstance(request, RunRequest)
    assert request.task == create.task and request.origin == "page"
    assert request.robot == (create.robot or "puma560")
    assert request.demonstrations == [demo]
    for field in ("planning", "planning_steps", "epsilon", "alpha", "gamma"):
        assert request.config[field] == getattr(create, field)
    assert (request.experiments, request.episodes, request.seed) == (
        create.experiments,
        create.episodes,
        create.seed,
    )
    assert list(request.goal_deg or []) == create.goal_deg
    assert request.name == (create.name or "")
    if create.task == "arm-reach":
        assert request.grid == {}
        assert request.reach == {
            "joints": create.joints,
            "step_deg": create.step_deg,
            "actions": create.actions,
            "tilings": create.tilings,
            "tiles": create.tiles,
        }
    else:
        assert request.reach == {} and request.grid == {"bins": create.bins}
    if not form.get("robot"):  # (another robot's grid replays no Puma560 path)
        no_demos = create.request("puma560")
        record = resolve_run(no_demos)
        again = RUN_CREATE.validate_python(record.form())
        assert again.task == create.task and again.planning == create.planning
        assert again.episodes == create.episodes and again.seed == create.seed
