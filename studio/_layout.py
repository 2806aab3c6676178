"""The data folder's layout: where the studio keeps what a user makes and what it caches.

One definition for ``studio serve`` (the page), the command-line verbs and the exports, so that a
recording made by one is found by the others.
"""

from __future__ import annotations

import os
from pathlib import Path

RECORDINGS_DIR = "recordings"
"""Where a data folder keeps its recordings and the demonstrations cut from them."""
POLICIES_DIR = "policies"
"""Where a data folder keeps uploaded policy files."""
RUNS_DIR = "runs"
"""Where a data folder keeps training runs (each with ``policy.policy.npz``)."""
CACHE_DIR = "cache"
"""Where a data folder keeps what the studio can always rebuild (safe to delete)."""


def mesh_cache_dir(data_dir: str | os.PathLike[str]) -> Path:
    """Where the drawn robots' simplified meshes are kept (a cache: safe to delete)."""
    return Path(data_dir) / CACHE_DIR / "meshes"


def robot_cache_dir(data_dir: str | os.PathLike[str]) -> Path:
    """Where the robots' built models and collision hulls are kept (a cache: safe to delete)."""
    return Path(data_dir) / CACHE_DIR / "robots"


def physics_cache_dir(data_dir: str | os.PathLike[str]) -> Path:
    """Where the robots' MuJoCo files (their URDF folders, converted meshes) are kept (a cache:
    safe to delete)."""
    return Path(data_dir) / CACHE_DIR / "physics"
