"""A camera frame crosses the web layer as the API parsed it (a typed object, not a dict), and
the camera source alone checks its values."""

from __future__ import annotations

from fastapi.testclient import TestClient

from studio.web._schemas import LandmarksFrame, LandmarksPublic

from .test_teachers import camera, landmarks


def test_the_studio_gets_the_parsed_frame_and_answers_typed(client: TestClient, monkeypatch):
    camera(client)
    studio = client.app.state.studio.sources  # the service the route hands the frame to
    handed: list[object] = []
    answered: list[object] = []
    post = studio.post_landmarks

    def spy(frame: object) -> object:
        handed.append(frame)
        answered.append(post(frame))
        return answered[-1]

    monkeypatch.setattr(studio, "post_landmarks", spy)
    r = client.post("/api/source/landmarks", json=landmarks())
    assert r.status_code == 200, r.text
    assert isinstance(handed[0], LandmarksFrame) and isinstance(answered[0], LandmarksPublic)
    assert r.json() == answered[0].model_dump()


def test_a_wrong_size_is_the_camera_sources_one_sentence(client: TestClient):
    """The schema parses; the sizes are judged once, by capture (its sentence, 422), whether
    too few landmarks or too many."""
    camera(client)
    for rows in (32, 34):
        frame = landmarks()
        frame["world"] = (frame["world"] * 2)[:rows]
        r = client.post("/api/source/landmarks", json=frame)
        assert r.status_code == 422
        detail = r.json()["detail"]
        assert isinstance(detail, str) and "33 landmarks" in detail, detail
