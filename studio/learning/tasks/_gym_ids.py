"""The Gymnasium ids of the two arm tasks, their episode caps, and their registration.

Kept apart from the environments (:mod:`._gym`) so that ``import studio.learning`` registers them
at no cost: the registration waits for Gymnasium's own import (:func:`register_when_imported`),
and the environments, and with them numba and the robot models, load when one is made
(``gymnasium.make(ARM_REACH_ID)``).
"""

from __future__ import annotations

import importlib.abc
import importlib.util
import sys
from collections.abc import Sequence
from importlib.machinery import ModuleSpec
from types import ModuleType

ARM_GRID_ID = "TeachStudio/ArmGrid-v0"
ARM_REACH_ID = "TeachStudio/ArmReach-v0"
ARM_GRID_MAX_EPISODE_STEPS = 10_000
"""Episode cap of the registered grid environment (the paper's first episodes take ~2500)."""
DEFAULT_MAX_EPISODE_STEPS = 3_000
"""Episode cap of the registered reach environment (about three times the longest greedy path)."""
ENVIRONMENTS = "studio.learning.tasks._gym"
"""The module that defines the environments' classes."""


def register() -> None:
    """Register both environments with Gymnasium (idempotent)."""
    import gymnasium

    registry = gymnasium.envs.registration.registry
    if ARM_GRID_ID not in registry:
        gymnasium.register(
            ARM_GRID_ID,
            entry_point=f"{ENVIRONMENTS}:ArmGridEnv",
            max_episode_steps=ARM_GRID_MAX_EPISODE_STEPS,
        )
    if ARM_REACH_ID not in registry:
        gymnasium.register(
            ARM_REACH_ID,
            entry_point=f"{ENVIRONMENTS}:ArmReachEnv",
            max_episode_steps=DEFAULT_MAX_EPISODE_STEPS,
        )


def register_when_imported() -> None:
    """Register both environments as soon as Gymnasium is imported: now if it is, else right
    after its own import (in whichever module imports it first).

    ``import studio.learning`` so keeps its promise (``gymnasium.make(ARM_REACH_ID)`` works after
    it) without importing Gymnasium, and numpy with it: ``studio train --help`` reads the
    package's defaults in a fraction of a second.
    """
    if "gymnasium" in sys.modules:
        register()
    elif not any(isinstance(finder, _RegisterAfterImport) for finder in sys.meta_path):
        sys.meta_path.insert(0, _RegisterAfterImport())


class _RegisterAfterImport(importlib.abc.MetaPathFinder):
    """An import finder that finds Gymnasium as the others do, and has its loader call
    :func:`register` once Gymnasium's module has run (then leaves the import system)."""

    def __init__(self) -> None:
        self._finding = False

    def find_spec(
        self, fullname: str, path: Sequence[str] | None = None, target: ModuleType | None = None
    ) -> ModuleSpec | None:
        if fullname != "gymnasium" or self._finding:
            return None
        self._finding = True
        try:
            spec = importlib.util.find_spec(fullname)  # by the finders after this one
        finally:
            self._finding = False
        loader = None if spec is None else spec.loader
        if loader is None or not hasattr(loader, "exec_module"):
            return spec
        run_module = loader.exec_module

        def run_then_register(module: ModuleType) -> None:
            del loader.exec_module  # the loader's own method again (a retry finds it unpatched)
            run_module(module)
            if self in sys.meta_path:
                sys.meta_path.remove(self)
            register()

        loader.exec_module = run_then_register  # type: ignore[method-assign]
        return spec
