"""Plain-Python Dyna-Q: a line-by-line transcription of the paper's Fig. 1, the speed baseline.

No numpy in the loop, lists and dicts only, Python's own ``random``: what a careful first version
in Python looks like. It learns the same task with the same settings and planners (zero, full,
soft) as :mod:`studio.learning`, so ``bench_dynaq.py`` can compare their speed on equal work.
"""

from __future__ import annotations

import random
import time


def run_experiment(
    next_state: list[list[int]],
    reward: list[list[float]],
    terminal: list[bool],
    start_states: list[int],
    *,
    planning: str,
    planning_steps: int,
    episodes: int,
    seed: int,
    demonstrations: list[list[int]] | None = None,
    alpha: float = 0.1,
    gamma: float = 0.95,
    epsilon: float = 0.1,
) -> tuple[list[int], float]:
    """One experiment; returns (steps per episode, CPU seconds)."""
    start_cpu = time.process_time()
    rng = random.Random(seed)
    n_states, n_actions = len(next_state), len(next_state[0])
    q = [[0.0] * n_actions for _ in range(n_states)]
    model: dict[tuple[int, int], tuple[int, float]] = {}
    visited: list[tuple[int, int]] = []
    demos = demonstrations or []
    steps_per_episode = []
    for episode in range(episodes):
        if planning == "zero":
            n = 0
        elif planning == "soft":
            n = max(planning_steps - episode, 0)
        else:
            n = planning_steps
        demo = demos[episode] if episode < len(demos) else None
        s = demo[0] if demo else rng.choice(start_states)
        steps = 0
        while not terminal[s]:
            if demo:
                a = next_state[s].index(demo[steps + 1])
            elif rng.random() < epsilon:
                a = rng.randrange(n_actions)
            else:
                best = max(q[s])
                a = rng.choice([b for b in range(n_actions) if q[s][b] == best])
            s2, r = next_state[s][a], reward[s][a]
            q[s][a] += alpha * (r + gamma * (0.0 if terminal[s2] else max(q[s2])) - q[s][a])
            if (s, a) not in model:
                visited.append((s, a))
            model[(s, a)] = (s2, r)
            for _ in range(n):
                ps, pa = visited[rng.randrange(len(visited))]
                ps2, pr = model[(ps, pa)]
                target = pr + gamma * (0.0 if terminal[ps2] else max(q[ps2]))
                q[ps][pa] += alpha * (target - q[ps][pa])
            s = s2
            steps += 1
        steps_per_episode.append(steps)
    return steps_per_episode, time.process_time() - start_cpu
