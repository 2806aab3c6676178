"""Plain-Python linear Dyna-Q with tile coding: the speed baseline and the learner's test oracle.

A line-by-line transcription of semi-gradient Q-learning with tile-coded features (Sutton & Barto,
section 10.1, with Q-learning's max target) and Dyna planning from a sample model of the visited
transitions, as :mod:`studio.learning.linear._linear` describes it: lists and floats only, the
environment's own ``step``, and the same splitmix64 draws, so on the same seed it must give the
same weights bit for bit (``tests/learning/test_linear.py``), and ``bench_tiles.py`` compares
speed on equal work. Planners: zero, full and soft (prioritized sweeping is not transcribed).
"""

from __future__ import annotations

import math
import time
from typing import Any

MASK = (1 << 64) - 1
GOLDEN = 0x9E3779B97F4A7C15


def _mix(z: int) -> int:
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & MASK
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & MASK
    return z ^ (z >> 31)


def _below(z: int, n: int) -> int:
    return (((z >> 32) * n) & MASK) >> 32


def _unit(z: int) -> float:
    return float(z >> 11) * (1.0 / 9007199254740992.0)


class Tiles:
    """Tile coding of a box: ``tilings`` offset grids of ``tiles`` per dimension (see _tiles.py)."""

    def __init__(
        self,
        low: list[float],
        high: list[float],
        tilings: int,
        tiles: int,
        groups: list[list[int]],
        size: int,
    ) -> None:
        self.low, self.high = low, high
        self.scale = [tiles / (h - lo) for lo, h in zip(low, high, strict=True)]
        dims = len(low)
        self.shifts = [
            [((t * (2 * d + 1)) % tilings) / tilings for d in range(dims)] for t in range(tilings)
        ]
        width = tiles + 1
        self.groups = groups
        self.strides = []
        self.bases = []
        base = 0
        for g in groups:
            per_tiling = width ** len(g)
            self.strides.append({d: width**rank for rank, d in enumerate(g)})
            self.bases.append([base + t * per_tiling for t in range(tilings)])
            base += tilings * per_tiling
        self.size = size
        self.hashed = base > size

    def active(self, obs: list[float]) -> list[int]:
        out = []
        for g, strides in enumerate(self.strides):
            for t, shift in enumerate(self.shifts):
                plain = self.bases[g][t]
                for d in range(len(obs)):
                    if d not in strides:
                        continue
                    u = (min(max(obs[d], self.low[d]), self.high[d]) - self.low[d]) * self.scale[d]
                    plain += math.floor(u + shift[d]) * strides[d]
                if self.hashed:
                    plain = _mix((plain + GOLDEN) & MASK) % self.size
                out.append(plain)
        return out


def run_experiment(
    env: Any,
    tiles: Tiles,
    n_actions: int,
    *,
    episodes: int,
    rng: int,
    reset_seed: int,
    alpha: float,
    gamma: float,
    epsilon: float,
    planning: str = "zero",
    planning_steps: int = 0,
    max_steps: int = 10**9,
) -> tuple[list[list[float]], list[int], float]:
    """One experiment; returns (weights, steps per episode, CPU seconds)."""
    start_cpu = time.process_time()
    w = [[0.0] * n_actions for _ in range(tiles.size)]
    step = alpha / (len(tiles.groups) * len(tiles.shifts))
    model: list[tuple[list[float], int, float, bool, list[float]]] = []

    def q_values(feats: list[int]) -> list[float]:
        q = [0.0] * n_actions
        for f in feats:
            row = w[f]
            for a in range(n_actions):
                q[a] += row[a]
        return q

    def update(feats: list[int], a: int, r: float, terminal: bool, feats_next: list[int]) -> None:
        target = r
        if not terminal:
            target += gamma * max(q_values(feats_next))
        value = 0.0
        for f in feats:
            value += w[f][a]
        change = step * (target - value)
        for f in feats:
            w[f][a] += change

    steps_out = []
    for episode in range(episodes):
        if planning == "zero":
            n_plan = 0
        elif planning == "soft":
            n_plan = max(planning_steps - episode, 0)
        else:
            n_plan = planning_steps
        obs, _ = env.reset(seed=reset_seed if episode == 0 else None)
        obs = [float(x) for x in obs]
        feats = tiles.active(obs)
        steps = 0
        while steps < max_steps:
            # epsilon-greedy, ties broken uniformly
            rng = (rng + GOLDEN) & MASK
            if _unit(_mix(rng)) < epsilon:
                rng = (rng + GOLDEN) & MASK
                a = _below(_mix(rng), n_actions)
            else:
                q = q_values(feats)
                best = max(q)
                tied = [b for b in range(n_actions) if q[b] == best]
                k = 0
                if len(tied) > 1:
                    rng = (rng + GOLDEN) & MASK
                    k = _below(_mix(rng), len(tied))
                a = tied[k]
            obs_next, r, terminated, truncated, _ = env.step(a)
            obs_next = [float(x) for x in obs_next]
            feats_next = tiles.active(obs_next)
            update(feats, a, float(r), bool(terminated), feats_next)
            if planning != "zero" and planning_steps > 0:
                model.append((obs, a, float(r), bool(terminated), obs_next))
                for _ in range(n_plan):
                    rng = (rng + GOLDEN) & MASK
                    s, pa, pr, pt, s2 = model[_below(_mix(rng), len(model))]
                    update(tiles.active(s), pa, pr, pt, tiles.active(s2))
            steps += 1
            if terminated or truncated:
                break
            obs, feats = obs_next, feats_next
        steps_out.append(steps)
    return w, steps_out, time.process_time() - start_cpu
