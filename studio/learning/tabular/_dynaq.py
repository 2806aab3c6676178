"""Dyna-Q (the paper's Fig. 1) with four planners, run as many independent experiments.

Reads top to bottom like the paper's algorithm box:

1. small pure step functions: the Q-learning update of Eq. 1 (keeping each state's greedy value
   cached), the greedy choice with ties broken at random, the queueing of prioritized sweeping;
2. :func:`_run_experiment`, one experiment of ``episodes`` episodes: act, learn, update the model,
   plan; it writes each episode's step count as soon as the episode ends (live curves) and stops
   at an episode boundary when asked;
3. :func:`run_tabular_experiments`, which validates the input, turns demonstrations into action
   lists and spreads experiments over a thread pool (the kernels release the GIL).
   :func:`studio.learning.run_experiments` (:mod:`._experiments`) calls it for a
   :class:`TabularMDP`.

The random numbers (splitmix64, one generator per experiment), the priority queue and the run
around the kernels (:class:`LiveProgress`, :class:`ExperimentResult`) are the linear learner's
too: they live in :mod:`._learner`.

Planners (``DynaQConfig.planning``):

- ``zero``: Q-learning only.
- ``full``: after each real step, exactly ``planning_steps`` updates, each on a (state, action)
  drawn uniformly among those visited so far (the paper's Dyna-Q).
- ``soft``: like full, but episode ``k`` (from 0) plans ``max(planning_steps - k, 0)`` times per step.
- ``prioritized``: prioritized sweeping (Sutton & Barto, section 8.4). Every Q update, real or
  planned, queues the predecessors of the updated state whose own update would change Q by more than
  ``priority_threshold``; after each real step up to ``planning_steps`` queued pairs are updated,
  highest priority first. Two departures from the book's box: the real step's update is applied
  directly (as in Dyna-Q) rather than queued, so prioritized with 0 planning steps is exactly
  Q-learning; and since with alpha < 1 an update removes only part of a pair's error, the pair is
  queued again with what remains (the book's box assumes the error is gone, which with the paper's
  alpha = 0.1 leaves values far from converged).

The model is deterministic, as the MDP is: ``Model(s, a)`` stores the observed next state and reward.

Speed: the step functions are inlined into the kernel (numba ``inline="always"``). A numba call that
passes arrays updates their reference counts atomically on the way in and out, which cost more than
the step itself; inlined, a planning update is ~10 ns and a real step a few tens of ns. The kernel
takes its arguments in named tuples (:data:`Dynamics`, :data:`Learning`, :data:`Demonstrations`),
as the linear learner's does.

Caching caveat: numba's disk cache of the kernel is keyed on this file alone, yet it compiles in
the helpers of ``_learner.py``; after editing that file, touch this one (or delete
``__pycache__/_dynaq*.nb*``) so the kernel recompiles.
"""

from __future__ import annotations

import time
from collections import namedtuple
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np
from numba import njit

from .._config import DynaQConfig
from .._errors import LearningError
from .._learner import (
    GOLDEN,
    PLANNER_CODE,
    PRIORITIZED,
    ExperimentResult,
    LiveProgress,
    below,
    check_run_arguments,
    experiment_seed,
    heap_pop,
    heap_push,
    lower_thread_priority,
    mix,
    plan_budget,
    result_so_far,
    unit,
)
from ..tasks._mdp import TabularMDP

Dynamics = namedtuple("Dynamics", "next_state reward terminal start_states")
"""The task as the kernel reads it: a :class:`TabularMDP`'s arrays (see there)."""

Learning = namedtuple("Learning", "alpha gamma epsilon planner planning_steps max_steps threshold")
"""A :class:`DynaQConfig` as plain numbers: its planner by code (:data:`PLANNER_CODE`), its
episode cap as ``max_steps`` and its ``priority_threshold`` as ``threshold``."""

Demonstrations = namedtuple("Demonstrations", "actions offsets starts")
"""Demonstrations replayed as the first episodes: every action back to back (int64), where each
demonstration's actions begin (int64, ``n + 1``) and its first state (int64, ``n``)."""

# --------------------------------------------------------------------------- step functions


@njit(nogil=True, cache=True, inline="always")
def _q_update(q, v, n_max, idx, s, s_next, r, alpha, gamma, n_actions):
    """Eq. 1 on Q(s, a) (flat index ``idx``), keeping ``v[s] = max_a Q(s, a)`` exact.

    ``v`` caches each state's greedy value so the target costs one lookup instead of a scan of
    the next state's row, and ``n_max[s]`` counts the entries of row ``s`` equal to it, so the row
    is rescanned only when its last maximal entry went down. Terminal states are never acted
    from, so their row and value stay 0 (nothing follows them).
    """
    old = q[idx]
    new = old + alpha * (r + gamma * v[s_next] - old)
    q[idx] = new
    best = v[s]
    if new > best:
        v[s] = new
        n_max[s] = 1
    elif new == best:
        if old != best:
            n_max[s] += 1
    elif old == best:
        n_max[s] -= 1
        if n_max[s] == 0:
            row = s * n_actions
            best = q[row]
            count = 1
            for b in range(row + 1, row + n_actions):
                if q[b] > best:
                    best = q[b]
                    count = 1
                elif q[b] == best:
                    count += 1
            v[s] = best
            n_max[s] = count


@njit(nogil=True, cache=True, inline="always")
def _greedy_with_ties(q, row, best, ties, n_actions, rng):
    """argmax_a Q(s, a) with ties broken uniformly at random; returns (action, rng).

    ``row`` is the flat index of Q(s, 0), ``best = max_a Q(s, a)`` and ``ties`` the number of
    actions equal to it (the kernel keeps both per state), so one draw picks the k-th tied action.
    When every action ties, that is action k; otherwise one pass over the row finds it, written
    without an early exit because the tied positions are random and a data-dependent branch would
    be mispredicted at almost every step.
    """
    if ties == 1:
        k = 0
    else:
        rng += GOLDEN
        k = below(mix(rng), ties)
        if ties == n_actions:
            return k, rng
    pick = 0
    count = 0
    for b in range(n_actions):
        hit = q[row + b] == best
        if hit and count == k:
            pick = b
        count += hit
    return pick, rng


@njit(nogil=True, cache=True, inline="always")
def _queue_pair(q, v, idx, s_next, r, gamma, threshold, heap_idx, heap_pri, pos, size):
    """Queue (s, a) (flat index ``idx``) with its remaining error if it exceeds the threshold."""
    priority = abs(r + gamma * v[s_next] - q[idx])
    if priority > threshold:
        size = heap_push(heap_idx, heap_pri, pos, size, idx, priority)
    return size


@njit(nogil=True, cache=True, inline="always")
def _queue_predecessors(
    q, v, s, gamma, threshold, pred_head, pred_link, model_next, model_reward,
    heap_idx, heap_pri, pos, size,
):  # fmt: skip
    """Queue every known (s_bar, a_bar) leading to ``s`` whose update would exceed the threshold."""
    p = pred_head[s]
    while p >= 0:
        priority = abs(model_reward[p] + gamma * v[s] - q[p])
        if priority > threshold:
            size = heap_push(heap_idx, heap_pri, pos, size, p, priority)
        p = pred_link[p]
    return size


# --------------------------------------------------------------------------- one experiment


@njit(nogil=True, cache=True)
def _run_experiment(task, learning, demos, seed, stop, steps_out, updates_out, q):
    """One Dyna-Q experiment; fills ``steps_out``/``updates_out``/``q`` and returns episodes done.

    ``task`` is a :data:`Dynamics`, ``learning`` a :data:`Learning`, ``demos`` a
    :data:`Demonstrations`; ``seed`` the experiment's generator state (uint64). Every array is
    C-contiguous: ``stop`` int64 (1,) (non-zero: stop at the next episode boundary),
    ``steps_out`` and ``updates_out`` int64 (episodes,), ``q`` float64 (S, A), zero on entry.

    One function of about 130 lines, on purpose: with its action choice, its model update and its
    planning loops moved into inlined helpers, a real step took about twice as long (CPU per
    zero-planning experiment on the arm grid 1.4 -> 3.0 ms; most likely the reference counting of
    the arrays handed to a helper that holds a loop, which numba does not prune).
    """
    next_state, reward, terminal, start_states = task
    alpha, gamma, epsilon, planner, planning_steps, max_steps, threshold = learning
    demo_actions, demo_offsets, demo_starts = demos
    n_states, n_actions = next_state.shape
    n_pairs = n_states * n_actions
    episodes = steps_out.shape[0]
    n_demos = demo_starts.shape[0]
    nxt = next_state.reshape(n_pairs)
    rew = reward.reshape(n_pairs)
    qf = q.reshape(n_pairs)

    v = np.zeros(n_states, np.float64)  # max_a Q(s, a), kept exact by _q_update
    n_max = np.full(n_states, n_actions, np.int64)  # entries of each row equal to v
    seen = np.zeros(n_pairs, np.bool_)
    # the model in order of first visit as rows (idx, s, s', r), stored as float64 (exact for
    # indices below 2**53) so that one 32-byte row, one cache line, holds all a uniform draw needs
    visited = np.empty((n_pairs, 4), np.float64)
    n_visited = 0
    prioritized = planner == PRIORITIZED
    queue_len = n_pairs if prioritized else 0
    model_next = np.empty(queue_len, np.int64)  # the model by flat (s, a), for the sweeps
    model_reward = np.empty(queue_len, np.float64)
    pred_head = np.full(n_states if prioritized else 0, -1, np.int64)
    pred_link = np.full(queue_len, -1, np.int64)
    heap_idx = np.empty(queue_len, np.int64)
    heap_pri = np.empty(queue_len, np.float64)
    pos = np.full(queue_len, -1, np.int64)
    heap_size = 0
    rng = seed

    done = 0
    for episode in range(episodes):
        if stop[0] != 0:
            break
        n_plan = plan_budget(planner, planning_steps, episode)
        demo = episode < n_demos
        if demo:
            s = demo_starts[episode]
            first_action = demo_offsets[episode]
            limit = demo_offsets[episode + 1] - first_action
        else:
            rng += GOLDEN
            s = start_states[below(mix(rng), start_states.shape[0])]
            first_action = 0
            limit = max_steps
        steps = 0
        updates = 0
        while not terminal[s] and steps < limit:
            # act: the demonstrated action, or epsilon-greedy
            if demo:
                a = demo_actions[first_action + steps]
            else:
                rng += GOLDEN
                if unit(mix(rng)) < epsilon:
                    rng += GOLDEN
                    a = below(mix(rng), n_actions)
                else:
                    a, rng = _greedy_with_ties(qf, s * n_actions, v[s], n_max[s], n_actions, rng)
            idx = s * n_actions + a
            s_next = nxt[idx]
            r = rew[idx]
            # model: remember the outcome of a first visit
            if not seen[idx]:
                seen[idx] = True
                visited[n_visited, 0] = idx
                visited[n_visited, 1] = s
                visited[n_visited, 2] = s_next
                visited[n_visited, 3] = r
                n_visited += 1
                if prioritized:
                    model_next[idx] = s_next
                    model_reward[idx] = r
                    pred_link[idx] = pred_head[s_next]
                    pred_head[s_next] = idx
            # learn: Eq. 1
            _q_update(qf, v, n_max, idx, s, s_next, r, alpha, gamma, n_actions)
            updates += 1
            # plan
            if prioritized:
                heap_size = _queue_pair(
                    qf, v, idx, s_next, r, gamma, threshold, heap_idx, heap_pri, pos, heap_size
                )
                heap_size = _queue_predecessors(
                    qf, v, s, gamma, threshold, pred_head, pred_link, model_next, model_reward,
                    heap_idx, heap_pri, pos, heap_size,
                )  # fmt: skip
                for _ in range(n_plan):
                    if heap_size == 0:
                        break
                    p, heap_size = heap_pop(heap_idx, heap_pri, pos, heap_size)
                    ps = p // n_actions
                    _q_update(
                        qf, v, n_max, p, ps, model_next[p], model_reward[p], alpha, gamma, n_actions
                    )
                    updates += 1
                    heap_size = _queue_pair(
                        qf, v, p, model_next[p], model_reward[p], gamma, threshold,
                        heap_idx, heap_pri, pos, heap_size,
                    )  # fmt: skip
                    heap_size = _queue_predecessors(
                        qf, v, ps, gamma, threshold, pred_head, pred_link, model_next,
                        model_reward, heap_idx, heap_pri, pos, heap_size,
                    )  # fmt: skip
            else:
                for _ in range(n_plan):
                    rng += GOLDEN
                    k = below(mix(rng), n_visited)
                    _q_update(
                        qf, v, n_max, np.int64(visited[k, 0]), np.int64(visited[k, 1]),
                        np.int64(visited[k, 2]), visited[k, 3], alpha, gamma, n_actions,
                    )  # fmt: skip
                updates += n_plan
            s = s_next
            steps += 1
        updates_out[episode] = updates
        steps_out[episode] = steps
        done += 1
    return done


# --------------------------------------------------------------------------- the tabular learner


def demonstration_actions(
    mdp: TabularMDP, demonstrations: Sequence[Sequence[int] | np.ndarray]
) -> Demonstrations:
    """Turn state sequences into the actions that connect them.

    Args:
        mdp: the task.
        demonstrations: each a sequence of states, consecutive states one action apart, ending in
            a terminal state (and passing through none before).

    Returns:
        ``(actions, offsets, starts)``: all actions back to back, where each demonstration's actions
        begin (length n + 1), and each demonstration's first state.

    Raises:
        LearningError: naming the demonstration and the step that breaks.
    """
    actions: list[np.ndarray] = []
    offsets = [0]
    starts = []
    for i, demo in enumerate(demonstrations):
        try:
            path = np.asarray(demo, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            raise LearningError(
                f"Demonstration {i} is not a sequence of state numbers; give a list of integers."
            ) from None
        if path.size == 0:
            raise LearningError(f"Demonstration {i} is empty; give at least its final state.")
        if not np.all(np.isfinite(path)) or np.any(path != np.round(path)):
            raise LearningError(f"Demonstration {i} holds non-integer states; give state numbers.")
        path = path.astype(np.int64)
        bad = np.flatnonzero((path < 0) | (path >= mdp.n_states))
        if bad.size:
            k = int(bad[0])
            raise LearningError(
                f"Demonstration {i} breaks at step {k}: state {int(path[k])} is not in [0, {mdp.n_states - 1}]; give states of this task."
            )
        early = np.flatnonzero(mdp.terminal[path[:-1]])
        if early.size:
            k = int(early[0])
            raise LearningError(
                f"Demonstration {i} breaks at step {k}: state {int(path[k])} is terminal but the path goes on; end the demonstration there."
            )
        if not mdp.terminal[path[-1]]:
            raise LearningError(
                f"Demonstration {i} ends in state {int(path[-1])}, which is not terminal; extend it to the goal."
            )
        links = mdp.intended[path[:-1]] == path[1:, None]  # a move an obstacle blocks is tried
        broken = np.flatnonzero(~links.any(axis=1))
        if broken.size:
            k = int(broken[0])
            raise LearningError(
                f"Demonstration {i} breaks at step {k}: no action leads from state {int(path[k])} to state {int(path[k + 1])}; give consecutive states one action apart."
            )
        actions.append(np.argmax(links, axis=1).astype(np.int64))
        offsets.append(offsets[-1] + path.size - 1)
        starts.append(path[0])
    flat = np.concatenate(actions) if actions else np.zeros(0, np.int64)
    return Demonstrations(
        np.ascontiguousarray(flat, dtype=np.int64),
        np.asarray(offsets, dtype=np.int64),
        np.asarray(starts, dtype=np.int64),
    )


def warm_up() -> float:
    """Load (or, the first time ever, compile) the kernels; returns the seconds it took.

    The kernels are cached on disk, so this costs a fraction of a second after the first run; call
    it before timing a run so the timing measures learning only.
    """
    start = time.perf_counter()
    corridor = TabularMDP(
        np.array([[1], [1]]), np.array([[1.0], [0.0]]), np.array([False, True]), np.array([0])
    )
    for planning in ("full", "prioritized"):
        run_tabular_experiments(corridor, DynaQConfig(planning=planning, planning_steps=1), 1, 1, 0)
    return time.perf_counter() - start


def run_tabular_experiments(
    mdp: TabularMDP,
    config: DynaQConfig,
    experiments: int,
    episodes: int,
    seed: int,
    demonstrations: Sequence[Sequence[int] | np.ndarray] | None = None,
    *,
    workers: int | None = None,
    live: LiveProgress | None = None,
) -> ExperimentResult:
    """Tabular Dyna-Q on ``mdp`` (:func:`studio.learning.run_experiments` for a
    :class:`TabularMDP`, whose arguments it takes; ``demonstrations`` are state sequences)."""
    seed, workers, live = check_run_arguments(
        config, experiments, episodes, seed, workers, live, mdp.n_states, mdp.n_actions
    )
    demos = demonstration_actions(mdp, demonstrations or [])
    task = Dynamics(mdp.next_state, mdp.reward, mdp.terminal, mdp.start_states)
    learning = Learning(
        float(config.alpha),
        float(config.gamma),
        float(config.epsilon),
        PLANNER_CODE[config.planning],
        int(config.planning_steps),
        int(config.max_steps_per_episode),
        float(config.priority_threshold),
    )
    q = np.zeros((experiments, mdp.n_states, mdp.n_actions), np.float64)
    cpu_seconds = np.zeros(experiments, np.float64)

    def one(e: int) -> None:
        lower_thread_priority(live.niceness)
        with live.counting_cpu() as spent:
            _run_experiment(
                task, learning, demos, experiment_seed(seed, e), live._stop, live.steps[e],
                live.updates[e], q[e],
            )  # fmt: skip
        cpu_seconds[e] = spent[0]

    def so_far() -> ExperimentResult:
        return result_so_far(ExperimentResult, live, cpu_seconds, q, config, seed)

    live.snapshot = so_far
    workers = min(workers, experiments)
    if workers == 1:
        for e in range(experiments):
            one(e)
    else:
        with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="dynaq") as pool:
            for future in [pool.submit(one, e) for e in range(experiments)]:
                future.result()
    return replace(so_far(), stopped=live.stopped and bool(np.any(live.steps < 0)))
