"""Every operation of the API against its own OpenAPI schema, in process (schemathesis).

A few derandomized examples per operation, every check schemathesis has (no server error,
responses matching their declared schema, status codes and content types documented, ``Allow``
on 405, schema-violating requests refused, ...), so that a new route or a changed model cannot
answer 500 or drift from its schema unnoticed.

Left out, and why:

- ``GET /api/events``: the Server-Sent Events stream never ends by itself (the page keeps it
  open), so a generated request would wait for ever; ``tests/web/test_live.py`` covers it.
- the ``positive_data_acceptance`` check: it expects every schema-valid request to succeed, but
  some refusals are about content a schema cannot describe (an uploaded file that is not a
  recording, a segment that never reaches the goal, a name that does not exist); those are
  422/404/409 with one sentence by design.

The PATCH-racing-DELETE case the fuzzer once hit is tested deterministically below.
"""

from __future__ import annotations

import shutil
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
import schemathesis
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, settings
from schemathesis import checks
from schemathesis.python import asgi

import studio.web.services._store as recordings_router
from studio.web import create_app
from tests.web.conftest import make_settings

EXAMPLES_PER_OPERATION = 4
"""Enough to reach each operation's error paths; the whole run stays well under a minute."""
EXCLUDED_CHECKS = ("positive_data_acceptance",)


def _checks() -> list:
    checks.load_all_checks()
    return [c for c in checks.CHECKS.get_all() if c.__name__ not in EXCLUDED_CHECKS]


DATA_DIR = Path(tempfile.mkdtemp(prefix="studio-schemathesis-"))
"""The studio's data folder for this module (removed when the module's tests end)."""
schema = schemathesis.openapi.from_asgi("/openapi.json", create_app(make_settings(DATA_DIR)))
schema = schema.exclude(path="/api/events")


@pytest.fixture(scope="module", autouse=True)
def _stop_the_studio() -> Iterator[None]:
    yield
    asgi.shutdown_lifespans()  # schemathesis started the studio (its lifespan): stop it
    shutil.rmtree(DATA_DIR, ignore_errors=True)


@schema.parametrize()
@settings(
    max_examples=EXAMPLES_PER_OPERATION,
    derandomize=True,
    deadline=None,
    database=None,
    suppress_health_check=list(HealthCheck),
)
def test_every_operation_matches_its_schema(case: schemathesis.Case) -> None:
    case.call_and_validate(checks=_checks())


def test_a_notes_edit_racing_a_delete_is_a_404(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The file disappears between the PATCH's lookup and its write: a 404 sentence, not 500."""
    assert (
        client.post("/api/recordings/sample-reach-1/copy", json={"name": "mine"}).status_code == 201
    )
    real = recordings_router.update_recording_meta
    in_patch, deleted = threading.Event(), threading.Event()

    def racing(path: Path, **changes: object) -> object:
        in_patch.set()
        assert deleted.wait(30)
        return real(path, **changes)

    monkeypatch.setattr(recordings_router, "update_recording_meta", racing)
    answers: list = []
    patch = threading.Thread(
        target=lambda: answers.append(client.patch("/api/recordings/mine", json={"notes": "x"}))
    )
    patch.start()
    assert in_patch.wait(30)
    assert client.delete("/api/recordings/mine").status_code == 204
    deleted.set()
    patch.join(30)
    (answer,) = answers
    assert answer.status_code == 404, answer.text
    assert "mine" in answer.json()["detail"] or "deleted" in answer.json()["detail"]
    assert client.get("/api/recordings/mine").status_code == 404
