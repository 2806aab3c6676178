"""Shared set-up of the physics tests: the robots' MuJoCo files built once per session."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def physics_cache(tmp_path_factory):
    """The folder the robots' MuJoCo files are kept in for the session."""
    return tmp_path_factory.mktemp("physics-cache")
