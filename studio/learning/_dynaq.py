"""Dyna-Q (the paper's Fig. 1) with four planners, run as many independent experiments.

Reads top to bottom like the paper's algorithm box:

1. a tiny deterministic random number generator (splitmix64) so every experiment is reproducible
   bit for bit, whichever thread runs it;
2. small pure step functions: the Q-learning update of Eq. 1 (keeping each state's greedy value
   cached), the greedy choice with ties broken at random, a max-heap for prioritized sweeping;
3. :func:`_run_experiment`, one experiment of ``episodes`` episodes: act, learn, update the model,
   plan; it writes each episode's step count as soon as the episode ends (live curves) and stops
   at an episode boundary when asked;
4. :func:`run_experiments`, which validates the input, turns demonstrations into action lists and
   spreads experiments over a thread pool (the kernels release the GIL).

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
the step itself; inlined, a planning update is ~10 ns and a real step a few tens of ns.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import contextmanager, suppress
from dataclasses import dataclass, replace
from typing import Any, TypeVar

import numpy as np
from numba import njit

from ._config import PLANNERS, DynaQConfig, check_budget
from ._errors import LearningError
from ._mdp import TabularMDP
from ._tiles import TileCoding

R = TypeVar("R", bound="ExperimentResult")

_PLANNER_CODE = {name: code for code, name in enumerate(PLANNERS)}
MAX_NICENESS = 19
"""The lowest CPU priority Linux gives a thread."""
_ZERO, _FULL, _SOFT, _PRIORITIZED = (_PLANNER_CODE[name] for name in PLANNERS)

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_U11 = np.uint64(11)
_U27 = np.uint64(27)
_U30 = np.uint64(30)
_U31 = np.uint64(31)
_U32 = np.uint64(32)
_INV_2_53 = 1.0 / 9007199254740992.0

# --------------------------------------------------------------------------- random numbers


@njit(nogil=True, cache=True, inline="always")
def _mix(z: np.uint64) -> np.uint64:
    """splitmix64's output function: a well-mixed 64-bit word from the generator's counter."""
    z = (z ^ (z >> _U30)) * _MIX1
    z = (z ^ (z >> _U27)) * _MIX2
    return z ^ (z >> _U31)


@njit(nogil=True, cache=True, inline="always")
def _below(z: np.uint64, n: int) -> int:
    """An integer in [0, n) from a random word (Lemire's multiply-shift on the top 32 bits)."""
    return np.int64(((z >> _U32) * np.uint64(n)) >> _U32)


@njit(nogil=True, cache=True, inline="always")
def _unit(z: np.uint64) -> float:
    """A float in [0, 1) from a random word."""
    return np.float64(z >> _U11) * _INV_2_53


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
        rng += _GOLDEN
        k = _below(_mix(rng), ties)
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
def _heap_push(heap_idx, heap_pri, pos, size, idx, priority):
    """Queue ``idx`` with ``priority`` (or raise its priority if queued lower); returns the size."""
    i = pos[idx]
    if i < 0:
        i = size
        size += 1
    elif heap_pri[i] >= priority:
        return size
    while i > 0:  # sift up
        parent = (i - 1) >> 1
        if heap_pri[parent] >= priority:
            break
        heap_idx[i] = heap_idx[parent]
        heap_pri[i] = heap_pri[parent]
        pos[heap_idx[i]] = i
        i = parent
    heap_idx[i] = idx
    heap_pri[i] = priority
    pos[idx] = i
    return size


@njit(nogil=True, cache=True, inline="always")
def _heap_pop(heap_idx, heap_pri, pos, size):
    """Remove the highest-priority entry; returns (idx, new size)."""
    top = heap_idx[0]
    pos[top] = -1
    size -= 1
    if size == 0:
        return top, size
    idx = heap_idx[size]
    priority = heap_pri[size]
    i = 0
    while True:  # sift down
        child = 2 * i + 1
        if child >= size:
            break
        if child + 1 < size and heap_pri[child + 1] > heap_pri[child]:
            child += 1
        if heap_pri[child] <= priority:
            break
        heap_idx[i] = heap_idx[child]
        heap_pri[i] = heap_pri[child]
        pos[heap_idx[i]] = i
        i = child
    heap_idx[i] = idx
    heap_pri[i] = priority
    pos[idx] = i
    return top, size


@njit(nogil=True, cache=True, inline="always")
def _queue_pair(q, v, idx, s_next, r, gamma, threshold, heap_idx, heap_pri, pos, size):
    """Queue (s, a) (flat index ``idx``) with its remaining error if it exceeds the threshold."""
    priority = abs(r + gamma * v[s_next] - q[idx])
    if priority > threshold:
        size = _heap_push(heap_idx, heap_pri, pos, size, idx, priority)
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
            size = _heap_push(heap_idx, heap_pri, pos, size, p, priority)
        p = pred_link[p]
    return size


# --------------------------------------------------------------------------- one experiment


@njit(nogil=True, cache=True)
def _run_experiment(
    next_state, reward, terminal, start_states,
    alpha, gamma, epsilon, planner, planning_steps, max_steps, threshold,
    demo_actions, demo_offsets, demo_starts,
    seed, stop, steps_out, updates_out, q,
):  # fmt: skip
    """One Dyna-Q experiment; fills ``steps_out``/``updates_out``/``q`` and returns episodes done.

    All arrays are C-contiguous: ``next_state`` int64 (S, A), ``reward`` float64 (S, A),
    ``terminal`` bool (S,), ``start_states`` int64, ``demo_actions`` int64 (all demonstrations'
    actions back to back), ``demo_offsets`` int64 (n_demos + 1), ``demo_starts`` int64 (n_demos,),
    ``stop`` int64 (1,) (non-zero: stop at the next episode boundary), ``steps_out`` and
    ``updates_out`` int64 (episodes,), ``q`` float64 (S, A), zero on entry.
    """
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
    prioritized = planner == _PRIORITIZED
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
        if planner == _ZERO:
            n_plan = 0
        elif planner == _SOFT:
            n_plan = max(planning_steps - episode, 0)
        else:
            n_plan = planning_steps
        demo = episode < n_demos
        if demo:
            s = demo_starts[episode]
            first_action = demo_offsets[episode]
            limit = demo_offsets[episode + 1] - first_action
        else:
            rng += _GOLDEN
            s = start_states[_below(_mix(rng), start_states.shape[0])]
            first_action = 0
            limit = max_steps
        steps = 0
        updates = 0
        while not terminal[s] and steps < limit:
            # act: the demonstrated action, or epsilon-greedy
            if demo:
                a = demo_actions[first_action + steps]
            else:
                rng += _GOLDEN
                if _unit(_mix(rng)) < epsilon:
                    rng += _GOLDEN
                    a = _below(_mix(rng), n_actions)
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
                    p, heap_size = _heap_pop(heap_idx, heap_pri, pos, heap_size)
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
                    rng += _GOLDEN
                    k = _below(_mix(rng), n_visited)
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


# --------------------------------------------------------------------------- the public API


class LiveProgress:
    """Shared, lock-free progress of a running :func:`run_experiments` call.

    The kernels write ``steps[e, k]`` (and ``updates[e, k]``) the moment episode ``k`` of
    experiment ``e`` ends; entries still -1 are not done yet. A web page polls these arrays from
    another thread to draw live curves, and calls :meth:`stop` to end the run at the next episode
    boundary.

    The learner also sets :attr:`snapshot` once its tables exist: the result so far, whose Q
    tables (or weights) are the very arrays the kernels update in place, so a checkpoint can save
    the policy learnt so far without stopping them (or copying every table).

    Args:
        experiments: number of experiments of the run this object will follow.
        episodes: episodes per experiment.
        niceness: how much lower the CPU priority of the threads running the kernels is
            (Linux ``nice``; 0 leaves it). A studio serving a page trains at a lower priority,
            so that a heavy run takes only the CPU its API, live pipeline and scene leave.
    """

    def __init__(self, experiments: int, episodes: int, niceness: int = 0) -> None:
        self.steps = np.full((experiments, episodes), -1, np.int64)
        self.updates = np.full((experiments, episodes), -1, np.int64)
        self.niceness = niceness
        self.note: str | None = None
        """A sentence on what the run does before its first episode (preparing the learner), or
        None once it learns."""
        self._stop = np.zeros(1, np.int64)
        self.snapshot: Callable[[], ExperimentResult] | None = None
        self._cpu_lock = threading.Lock()
        self._cpu_done = 0.0
        self._cpu_running: dict[int, float] = {}  # thread ident -> its CPU clock at start

    @contextmanager
    def counting_cpu(self) -> Iterator[list[float]]:
        """Count the calling thread's CPU time as this run's while the block runs (the kernels'
        threads wrap each experiment in it), so :attr:`cpu_seconds` grows live.

        Yields a one-element list that holds the block's CPU seconds once it ends.
        """
        ident = threading.get_ident()
        spent = [0.0]
        start = time.thread_time()
        with self._cpu_lock:
            self._cpu_running[ident] = start
        try:
            yield spent
        finally:
            spent[0] = time.thread_time() - start
            with self._cpu_lock:
                del self._cpu_running[ident]
                self._cpu_done += spent[0]

    @property
    def cpu_seconds(self) -> float:
        """CPU seconds the run's experiments have used so far, the ones still running included."""
        with self._cpu_lock:  # a thread leaves _cpu_running under this lock before it ends
            total = self._cpu_done
            for ident, start in self._cpu_running.items():
                with suppress(OSError, AttributeError, OverflowError):  # no per-thread clocks
                    total += time.clock_gettime(time.pthread_getcpuclockid(ident)) - start
        return total

    def stop(self) -> None:
        """Ask every experiment to stop at its next episode boundary."""
        self._stop[0] = 1

    @property
    def stopped(self) -> bool:
        """Whether :meth:`stop` was called."""
        return bool(self._stop[0])

    @property
    def completed(self) -> int:
        """Episodes finished so far, over all experiments."""
        return int(np.count_nonzero(self.steps >= 0))

    @property
    def total(self) -> int:
        """Episodes the run will do if not stopped."""
        return int(self.steps.size)


def result_so_far(
    kind: type[R],
    live: LiveProgress,
    cpu_seconds: np.ndarray,
    q: np.ndarray,
    config: DynaQConfig,
    seed: int,
    **extra: Any,
) -> R:
    """A learner's result as it stands: the progress so far, and ``q``, the tables the kernels
    are updating in place (not copied); ``stopped`` while episodes remain. Every learner builds
    its result, final or partial (:attr:`LiveProgress.snapshot`), through this."""
    return kind(
        steps=live.steps.copy(),
        updates=live.updates.copy(),
        cpu_seconds=cpu_seconds.copy(),
        q=q,
        config=config,
        seed=seed,
        stopped=bool(np.any(live.steps < 0)),
        **extra,
    )


def lower_thread_priority(niceness: int) -> None:
    """Run the calling thread ``niceness`` below the process's CPU priority (Linux, per thread).

    Only the threads that run the kernels call it: they hold no GIL while they compute, so
    the process's Python threads (a web server's) never wait for a low-priority thread holding
    it. Idempotent; a no-op for ``niceness <= 0`` and where threads have no priority of their own.
    """
    if niceness <= 0 or not hasattr(os, "setpriority") or sys.platform != "linux":
        return
    try:
        target = min(os.getpriority(os.PRIO_PROCESS, os.getpid()) + niceness, MAX_NICENESS)
        tid = threading.get_native_id()
        if os.getpriority(os.PRIO_PROCESS, tid) < target:
            os.setpriority(os.PRIO_PROCESS, tid, target)
    except OSError:  # never a reason not to train
        return


@dataclass(frozen=True, eq=False)
class ExperimentResult:
    """What :func:`run_experiments` returns.

    Attributes:
        steps: int ``(experiments, episodes)``: real steps per episode; -1 where the run was
            stopped before the episode ended.
        updates: int ``(experiments, episodes)``: Q updates per episode (real plus planning), -1
            where not done.
        cpu_seconds: float ``(experiments,)``: CPU time of each experiment's thread.
        q: float ``(experiments, S, A)``: the final Q tables.
        config: the settings used.
        seed: the seed used.
        stopped: whether the run was stopped early.
    """

    steps: np.ndarray
    updates: np.ndarray
    cpu_seconds: np.ndarray
    q: np.ndarray
    config: DynaQConfig
    seed: int
    stopped: bool

    @property
    def completed(self) -> np.ndarray:
        """bool ``(experiments, episodes)``: which episodes finished."""
        return self.steps >= 0

    def mean_steps(self) -> np.ndarray:
        """Mean steps per episode over the experiments that finished it (NaN where none did)."""
        done = self.completed
        total = np.where(done, self.steps, 0).sum(axis=0).astype(np.float64)
        count = done.sum(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(count > 0, total / np.maximum(count, 1), np.nan)

    def best_experiment(self, tail: float = 0.25) -> int:
        """Index of the experiment with the fewest mean steps over its last ``tail`` of episodes."""
        scores = []
        for row in self.steps:
            done = row[row >= 0]
            if done.size == 0:
                scores.append(np.inf)
                continue
            k = max(1, int(np.ceil(done.size * tail)))
            scores.append(float(done[-k:].mean()))
        return int(np.argmin(scores))


def demonstration_actions(
    mdp: TabularMDP, demonstrations: Sequence[Sequence[int]]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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
        links = mdp.next_state[path[:-1]] == path[1:, None]
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
    return (
        np.ascontiguousarray(flat, dtype=np.int64),
        np.asarray(offsets, dtype=np.int64),
        np.asarray(starts, dtype=np.int64),
    )


def experiment_seed(seed: int, experiment: int) -> np.uint64:
    """The generator seed of one experiment, derived from the run seed and its index."""
    return np.uint64(np.random.SeedSequence([seed, experiment]).generate_state(1, np.uint64)[0])


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
        run_experiments(corridor, DynaQConfig(planning=planning, planning_steps=1), 1, 1, 0)
    return time.perf_counter() - start


def check_run_arguments(
    config: object,
    experiments: object,
    episodes: object,
    seed: object,
    workers: object,
    live: object,
    n_states: int = 1,
    n_actions: int = 1,
) -> tuple[int, int, LiveProgress]:
    """Check the arguments every learner's ``run_experiments`` shares, before any work starts.

    Returns:
        ``(seed, workers, live)``: the seed as a plain int, the thread count (``None``: one per
        core), and the progress to fill (a new one when ``live`` is None).

    Raises:
        ConfigError, LearningError: one sentence naming the bad argument and the fix.
    """
    if not isinstance(config, DynaQConfig):
        raise LearningError(f"config is a {type(config).__name__}; give a DynaQConfig.")
    check_budget(experiments, episodes, n_states, n_actions)
    if not isinstance(seed, int | np.integer) or isinstance(seed, bool) or not 0 <= seed < 2**63:
        raise LearningError(f"seed is {seed!r}; give a whole number from 0 to 2**63 - 1.")
    if workers is None:
        workers = os.cpu_count() or 1
    if not isinstance(workers, int) or isinstance(workers, bool) or workers < 1:
        raise LearningError(f"workers is {workers!r}; give a whole number of threads, at least 1.")
    if live is None:
        live = LiveProgress(experiments, episodes)  # type: ignore[arg-type]
    elif not isinstance(live, LiveProgress) or live.steps.shape != (experiments, episodes):
        raise LearningError(
            f"live follows a run of shape {getattr(getattr(live, 'steps', None), 'shape', None)}; create LiveProgress({experiments}, {episodes}) for this run."
        )
    if live.completed:
        raise LearningError(
            "live already holds a finished run; create a new LiveProgress for each run."
        )
    return int(seed), workers, live


def run_experiments(
    mdp: TabularMDP,
    config: DynaQConfig,
    experiments: int,
    episodes: int,
    seed: int,
    demonstrations: Sequence[Sequence[int]] | None = None,
    features: TileCoding | None = None,
    *,
    workers: int | None = None,
    live: LiveProgress | None = None,
) -> ExperimentResult:
    """Run ``experiments`` independent Dyna-Q learners for ``episodes`` episodes each.

    Experiment ``e`` draws its random numbers from a generator seeded by ``(seed, e)``, so the
    result is identical bit for bit for a given seed whatever ``workers`` is. Experiments run on a
    pool of ``workers`` threads; the compiled kernels release the GIL.

    Args:
        mdp: the task.
        config: learning settings.
        experiments: independent repetitions to average over (the paper used 20).
        episodes: episodes per experiment.
        seed: a non-negative integer.
        demonstrations: state sequences replayed as the first ``len(demonstrations)`` episodes
            (the agent takes the demonstrated actions, learning and planning as usual).
        workers: threads to use (default: one per CPU core).
        live: progress arrays to fill while running, and the stop flag to obey.
        features: for a Gymnasium environment (a registered id or a zero-argument callable
            returning one, Box observations, Discrete actions) in place of ``mdp``: the tile
            coding of linear Dyna-Q (see :mod:`._linear`, which then runs the experiments and
            returns a :class:`LinearResult` with the learned weights).

    Returns:
        The step and update counts per episode, CPU seconds per experiment and the final Q tables.

    Raises:
        LearningError: for a bad argument, a bad demonstration or a run over the limits.
    """
    if not isinstance(mdp, TabularMDP) and (isinstance(mdp, str) or callable(mdp)):
        from ._linear import run_linear_experiments  # imports this module: import it late

        return run_linear_experiments(
            mdp, config, experiments, episodes, seed, demonstrations, features,
            workers=workers, live=live,
        )  # fmt: skip
    if not isinstance(mdp, TabularMDP):
        raise LearningError(
            f"mdp is a {type(mdp).__name__}; give a TabularMDP (for example ArmGrid().mdp()), a Gymnasium environment id or a zero-argument callable returning an environment."
        )
    seed, workers, live = check_run_arguments(
        config, experiments, episodes, seed, workers, live, mdp.n_states, mdp.n_actions
    )
    demo_actions, demo_offsets, demo_starts = demonstration_actions(mdp, demonstrations or [])

    q = np.zeros((experiments, mdp.n_states, mdp.n_actions), np.float64)
    cpu_seconds = np.zeros(experiments, np.float64)
    planner = _PLANNER_CODE[config.planning]

    def one(e: int) -> None:
        lower_thread_priority(live.niceness)
        with live.counting_cpu() as spent:
            _run_experiment(
                mdp.next_state, mdp.reward, mdp.terminal, mdp.start_states,
                float(config.alpha), float(config.gamma), float(config.epsilon), planner,
                int(config.planning_steps), int(config.max_steps_per_episode),
                float(config.priority_threshold),
                demo_actions, demo_offsets, demo_starts,
                experiment_seed(seed, e), live._stop, live.steps[e], live.updates[e], q[e],
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
