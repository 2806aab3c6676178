"""Dyna-Q with linear function approximation over tile-coded features.

Q(s, a) is the sum of the weights of s's active features in a's column of a ``(size, actions)``
table (:mod:`._tiles`; plus a column common to every action on a task that follows
demonstrations, :mod:`._common_value`). A real step applies the semi-gradient Q-learning update

    w[f, a] += (alpha / active) * (r + gamma * max_b Q(s', b) - Q(s, a))   for each active f of s

(the target is ``r`` alone when s' is terminal), dividing ``alpha`` among the active tilings as
Sutton & Barto do (their Mountain Car uses alpha = 0.5 / 8 with 8 tilings). The planners keep the
meaning they have in the tabular learner (:mod:`._dynaq`): ``zero`` none, ``full`` exactly
``planning_steps`` model updates per real step, ``soft`` ``max(planning_steps - k, 0)`` in
episode ``k``, ``prioritized`` at most ``planning_steps`` updates per real step, largest error first.

The model. Planning uses a **sample model over the visited transitions**: every real transition
``(s, a, r, s', terminal)`` is stored as it happened (the observations, not their features), and
a planning update replays one stored transition exactly as a real update would. We chose it over
the linear expectation model of Sutton, Szepesvari, Geramifard & Bowling (2008) because (1) it is
exact for the deterministic tasks here (the arm and Mountain Car) where the linear model (an F x F
matrix per action, F the feature count) is an approximation whose error compounds, (2) it is the
tabular learner's model, unchanged in meaning (its "previously visited (s, a)" are now the
visited transitions), and (3) it costs O(active x actions) per update rather than O(F) or O(F^2).
The model holds the last ``model_capacity`` transitions (a ring; older ones are forgotten). It is
built from the agent's own steps only; planning never calls the environment.

Prioritized sweeping over the sample model: each stored transition has a priority, its absolute
TD error when last looked at. After a real step the transition and its predecessor are queued
(as in :mod:`._dynaq`, the real update is applied directly, so prioritized with 0 steps is plain
Q-learning); each planning update pops the largest, applies it, and requeues it and its
predecessor with their remaining errors when above ``priority_threshold``. A transition's
predecessor is the stored step before it in the same episode (whose s' is its s): exact for a
sample model, and cheap; transitions that merely share features are reached when their own
priority comes up.

Where the dynamics run. For our arm task (``TeachStudio/ArmReach-v0``) and Gymnasium's
``MountainCar-v0`` the whole experiment runs in one compiled kernel (:func:`_run_compiled`) that
steps a numba twin of the environment's dynamics (:mod:`._linear_env`, which makes, checks and
recognises the environments). Every other environment with a Box observation and Discrete actions
runs a Python loop calling ``env.step`` and the same compiled learning step (:func:`_learn`), so
both paths give the same result bit for bit on the same task. Start states come from
``env.reset`` in both paths (seeded per experiment), so they agree too.

Random numbers: splitmix64 inside the kernels, as in the tabular learner (both take it, the
priority heap and the run around the kernels from :mod:`._learner`), seeded per experiment by
``(seed, experiment)``; the environment's resets by ``seed`` and the experiment index.

Caching caveat: numba's disk cache of these kernels is keyed on this file alone, yet they compile
in the dynamics of ``tasks/`` (``_reach``, ``_follow``, ``_chain``, ``_obstacles``, their layout)
and ``_env.py``, the features of ``_tiles.py``, the demonstrations' potential of
``_demo_shaping.py`` and the helpers of ``_learner.py``; after editing one, touch this file.
"""

from __future__ import annotations

from collections import namedtuple
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from .._config import MAX_Q_ENTRIES, DynaQConfig
from .._errors import LearningError
from .._learner import (
    GOLDEN,
    PLANNER_CODE,
    PRIORITIZED,
    ZERO,
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
from .._tiles import TileCoder, TileCoding, active_features
from ..tasks._demo_shaping import demo_potential, no_potential, potential, shaped
from ..tasks._follow import with_cost_group
from ..tasks._reach import ArmReach
from ._common_value import q_values as _q_values
from ._common_value import update_common, without_common
from ._env import (
    env_demonstrations,
    followed_task,
    make_env,
    observe,
    reset_seed,
    reset_states,
    task_step,
)
from ._factored import (
    FACTORED_ACTION_SETS,
    action_components,
    column_sums,
    expand,
    factored_add,
    factored_values,
    follow_add,
    no_components,
    reward_split,
    row_joints,
    slot_joints,
    split_reward,
)
from ._greedy import _greedy_episode as _greedy_episode
from ._greedy import greedy_rollout as greedy_rollout
from ._greedy import greedy_success as greedy_success

if TYPE_CHECKING:
    import gymnasium

DEFAULT_MODEL_CAPACITY = 1 << 18
"""Transitions the sample model keeps (a ring; about 100 bytes each for a 6-D observation)."""

Agent = namedtuple(
    "Agent",
    "w spec gamma step planner threshold "
    "model_obs model_next model_action model_reward model_terminal model_stamp model_follows "
    "heap_idx heap_pri heap_pos counters feats feats_next plan_s plan_next qvals comp slots sums split pot deltas "
    "whole_step",
)
"""The learner's arrays and settings as one numba-friendly value (see :func:`_new_agent`).

``comp`` ``(actions, J)``: each action's weight column per joint when the value is factored
(:mod:`._factored`), ``(actions, 0)`` for one column per action; ``slots`` the joint each active
feature slot feeds, ``split`` and ``pot`` what splits a reward among the joints, ``sums`` and
``deltas`` scratch; ``whole_step`` the step of a column every active feature feeds (the
factored value's follow column: ``alpha`` divided among all of them).

``counters`` int64: ``[stored, next slot, heap size, transitions ever stored]``.
"""
_STORED, _SLOT, _HEAP, _STAMP = 0, 1, 2, 3

Episodes = namedtuple(
    "Episodes",
    "starts demo_starts demo_actions demo_offsets max_steps planning_steps epsilon potential",
)
"""What the compiled kernel plays: start states ``(episodes, state_dim)``, demonstrations
(starts ``(n, state_dim)``, actions back to back, offsets ``(n + 1,)``), the step cap, the
planning budget, epsilon and the demonstrations' shaping potential (:mod:`._demo_shaping`)."""


# --------------------------------------------------------------------------- learning steps


@njit(nogil=True, cache=True, inline="always")
def _values(agent, feats, out):
    """``out[a] = Q(s, a)`` under the agent's weights, factored or one column per action."""
    if agent.comp.shape[1] == 0:
        _q_values(agent.w, feats, out)
    else:
        factored_values(agent.w, agent.comp, agent.slots, agent.sums, feats, out)


@njit(nogil=True, cache=True, inline="always")
def _value(agent, feats, action):
    """``Q(s, action)`` under the agent's weights."""
    value = 0.0
    common = agent.w.shape[1] > agent.qvals.shape[0]  # (the common column, :mod:`._common_value`)
    for i in range(feats.shape[0]):
        value += agent.w[feats[i], action]
        if common:
            value += agent.w[feats[i], agent.qvals.shape[0]]
    return value


@njit(nogil=True, cache=True, inline="always")
def _max(q):
    best = q[0]
    for a in range(1, q.shape[0]):
        if q[a] > best:
            best = q[a]
    return best


@njit(nogil=True, cache=True)
def _choose(q, epsilon, rng):
    """Epsilon-greedy on the action values ``q``, ties broken uniformly; returns ``(a, rng)``.

    Draws exactly as the tabular kernel does: one draw for exploration, then one for the random
    action or, when several actions tie for the best, one to pick among them.
    """
    n_actions = q.shape[0]
    rng += GOLDEN
    if unit(mix(rng)) < epsilon:
        rng += GOLDEN
        return below(mix(rng), n_actions), rng
    best = _max(q)
    ties = 0
    for a in range(n_actions):
        if q[a] == best:
            ties += 1
    k = 0
    if ties > 1:
        rng += GOLDEN
        k = below(mix(rng), ties)
    count = 0
    for a in range(n_actions):
        if q[a] == best:
            if count == k:
                return a, rng
            count += 1
    return 0, rng


@njit(nogil=True, cache=True)
def _factored_deltas(agent, obs, feats_s, action, reward, terminal, obs_next, feats_next):
    """Each joint term's TD error into ``agent.deltas`` (its share of the reward, plus gamma
    times its term at the next state's greedy action, minus its term now); returns their sum.

    The follow action (after the moves) has no joint terms: its TD error is returned alone. A
    move whose next greedy action is the follow action gives each joint an equal share of that
    action's value."""
    comp = agent.comp
    deltas = agent.deltas
    moves = comp.shape[0]
    q = agent.qvals
    if action >= moves:
        target = reward
        if not terminal:
            factored_values(agent.w, comp, agent.slots, agent.sums, feats_next, q)
            target += agent.gamma * _max(q)
        column_sums(agent.w, agent.slots, feats_s, agent.sums)
        return target - agent.sums[3 * comp.shape[1]]
    split_reward(agent.split, agent.pot, obs, obs_next, reward, terminal, deltas)
    if not terminal:
        factored_values(agent.w, comp, agent.slots, agent.sums, feats_next, q)
        best = 0
        for a in range(1, q.shape[0]):
            if q[a] > q[best]:
                best = a
        for j in range(comp.shape[1]):
            if best < moves:
                deltas[j] += agent.gamma * agent.sums[comp[best, j]]
            else:
                deltas[j] += agent.gamma * q[best] / comp.shape[1]
    column_sums(agent.w, agent.slots, feats_s, agent.sums)
    total = 0.0
    for j in range(comp.shape[1]):
        deltas[j] -= agent.sums[comp[action, j]]
        total += deltas[j]
    return total


@njit(nogil=True, cache=True)
def _td_update(agent, obs, feats_s, action, reward, terminal, obs_next, feats_next):
    """Semi-gradient Q-learning on one transition; returns the TD error before the update.

    With a factored value each joint's term learns from its own TD error (:mod:`._factored`)."""
    if agent.comp.shape[1] != 0:
        delta = _factored_deltas(
            agent, obs, feats_s, action, reward, terminal, obs_next, feats_next
        )
        if action >= agent.comp.shape[0]:  # the follow action: its own column
            follow_add(agent.w, feats_s, 3 * agent.comp.shape[1], agent.whole_step * delta)
            return delta
        for j in range(agent.deltas.shape[0]):
            agent.deltas[j] *= agent.step
        factored_add(agent.w, agent.comp, agent.slots, feats_s, action, agent.deltas)
        return delta
    q = agent.qvals
    target = reward
    if not terminal:
        _values(agent, feats_next, q)
        target += agent.gamma * _max(q)
    delta = target - _value(agent, feats_s, action)
    w = agent.w
    change = update_common(w, feats_s, q.shape[0], agent.step * delta)
    for i in range(feats_s.shape[0]):
        w[feats_s[i], action] += change
    return delta


@njit(nogil=True, cache=True)
def _error(agent, slot):
    """Absolute TD error of stored transition ``slot`` under the current weights."""
    active_features(agent.spec, agent.model_obs[slot], agent.plan_s)
    active_features(agent.spec, agent.model_next[slot], agent.plan_next)
    if agent.comp.shape[1] != 0:
        return abs(
            _factored_deltas(
                agent, agent.model_obs[slot], agent.plan_s, agent.model_action[slot],
                agent.model_reward[slot], agent.model_terminal[slot], agent.model_next[slot],
                agent.plan_next,
            )
        )  # fmt: skip
    q = agent.qvals
    target = agent.model_reward[slot]
    if not agent.model_terminal[slot]:
        _values(agent, agent.plan_next, q)
        target += agent.gamma * _max(q)
    return abs(target - _value(agent, agent.plan_s, agent.model_action[slot]))


@njit(nogil=True, cache=True)
def _replay(agent, slot):
    """One planning update: the stored transition ``slot`` replayed as a real update."""
    active_features(agent.spec, agent.model_obs[slot], agent.plan_s)
    active_features(agent.spec, agent.model_next[slot], agent.plan_next)
    _td_update(
        agent, agent.model_obs[slot], agent.plan_s, agent.model_action[slot],
        agent.model_reward[slot], agent.model_terminal[slot], agent.model_next[slot],
        agent.plan_next,
    )  # fmt: skip


@njit(nogil=True, cache=True)
def _queue(agent, slot):
    """Queue ``slot`` with its current error when that exceeds the threshold."""
    priority = _error(agent, slot)
    if priority > agent.threshold:
        agent.counters[_HEAP] = heap_push(
            agent.heap_idx, agent.heap_pri, agent.heap_pos, agent.counters[_HEAP], slot, priority
        )


@njit(nogil=True, cache=True)
def _queue_predecessor(agent, slot):
    """Queue the stored step before ``slot`` in the same episode, if the ring still holds it."""
    if not agent.model_follows[slot]:
        return
    capacity = agent.model_stamp.shape[0]
    prev = slot - 1 if slot > 0 else capacity - 1
    if agent.model_stamp[prev] == agent.model_stamp[slot] - 1:
        _queue(agent, prev)


@njit(nogil=True, cache=True)
def _store(agent, obs, action, reward, terminal, obs_next, follows):
    """Remember a real transition in the sample model; returns its slot."""
    slot = agent.counters[_SLOT]
    capacity = agent.model_stamp.shape[0]
    agent.model_obs[slot] = obs
    agent.model_next[slot] = obs_next
    agent.model_action[slot] = action
    agent.model_reward[slot] = reward
    agent.model_terminal[slot] = terminal
    agent.model_stamp[slot] = agent.counters[_STAMP]
    agent.model_follows[slot] = follows
    agent.counters[_STAMP] += 1
    agent.counters[_SLOT] = slot + 1 if slot + 1 < capacity else 0
    if agent.counters[_STORED] < capacity:
        agent.counters[_STORED] += 1
    return slot


@njit(nogil=True, cache=True)
def _learn(agent, obs, feats_s, action, reward, terminal, obs_next, follows, n_plan, rng):
    """A real step's learning: update, remember, plan. Returns ``(rng, updates)``.

    Leaves the active features of ``obs_next`` in ``agent.feats_next``.
    """
    active_features(agent.spec, obs_next, agent.feats_next)
    _td_update(agent, obs, feats_s, action, reward, terminal, obs_next, agent.feats_next)
    updates = 1
    if agent.model_stamp.shape[0] == 0:
        return rng, updates
    slot = _store(agent, obs, action, reward, terminal, obs_next, follows)
    if agent.planner == PRIORITIZED:
        _queue(agent, slot)
        _queue_predecessor(agent, slot)
        for _ in range(n_plan):
            if agent.counters[_HEAP] == 0:
                break
            p, agent.counters[_HEAP] = heap_pop(
                agent.heap_idx, agent.heap_pri, agent.heap_pos, agent.counters[_HEAP]
            )
            _replay(agent, p)
            updates += 1
            _queue(agent, p)
            _queue_predecessor(agent, p)
    else:
        stored = agent.counters[_STORED]
        for _ in range(n_plan):
            rng += GOLDEN
            _replay(agent, below(mix(rng), stored))
        updates += n_plan
    return rng, updates


@njit(nogil=True, cache=True)
def _act(agent, feats, epsilon, rng):
    """Epsilon-greedy action at the state with active ``feats``; returns ``(a, rng)``."""
    _values(agent, feats, agent.qvals)
    return _choose(agent.qvals, epsilon, rng)


# --------------------------------------------------------------------------- compiled tasks


@njit(nogil=True, cache=True)
def _run_compiled(task, params, agent, plays, seed, stop, steps_out, updates_out):
    """One experiment on a compiled task; fills ``steps_out``/``updates_out``, returns episodes."""
    episodes = steps_out.shape[0]
    n_demos = plays.demo_starts.shape[0]
    dims = plays.starts.shape[1]
    state = np.empty(dims)
    obs = np.empty(agent.spec.low.shape[0])  # the joints, and a followed task's cost
    obs_next = np.empty(agent.spec.low.shape[0])
    feats = np.empty(agent.feats.shape[0], np.int64)
    rng = seed
    done = 0
    for episode in range(episodes):
        if stop[0] != 0:
            break
        n_plan = plan_budget(agent.planner, plays.planning_steps, episode)
        demo = episode < n_demos
        if demo:
            state[:] = plays.demo_starts[episode]
            first = plays.demo_offsets[episode]
            limit = plays.demo_offsets[episode + 1] - first
        else:
            state[:] = plays.starts[episode]
            first = 0
            limit = plays.max_steps
        observe(task, params, state, obs)
        active_features(agent.spec, obs, feats)
        phi = potential(plays.potential, obs)
        steps = 0
        updates = 0
        while steps < limit:
            if demo:
                action = plays.demo_actions[first + steps]
            else:
                action, rng = _act(agent, feats, plays.epsilon, rng)
            reward, terminal = task_step(task, params, state, action)
            observe(task, params, state, obs_next)
            reward, phi = shaped(plays.potential, reward, phi, obs_next)
            rng, n = _learn(
                agent, obs, feats, action, reward, terminal, obs_next, steps > 0, n_plan, rng
            )
            updates += n
            steps += 1
            if terminal:
                break
            obs[:] = obs_next
            feats[:] = agent.feats_next
        steps_out[episode] = steps
        updates_out[episode] = updates
        done += 1
    return done


# --------------------------------------------------------------------------- set-up


def _new_agent(
    coder: TileCoder,
    n_actions: int,
    dims: int,
    config: DynaQConfig,
    capacity: int,
    weights: np.ndarray | None = None,
    factors: tuple | None = None,
) -> Agent:
    """Zero weights (``weights``, a zeroed ``(size, columns)`` table to learn into, when given),
    an empty model (none at all for zero planning) and scratch arrays. ``factors`` (from
    :func:`value_factors`) factors the value (:mod:`._factored`; None: one column per action)."""
    comp, slots, split, pot = factors or (
        no_components(n_actions),
        np.zeros(0, np.int64),
        np.zeros(0),
        no_potential(dims),
    )
    touched = coder.coding.tilings if comp.shape[1] else coder.n_active  # slots feeding a term
    if comp.shape[1] and n_actions > comp.shape[0]:
        touched *= 2  # the follow cost's slots feed every joint's term too (:mod:`._factored`)
    columns = n_actions if comp.shape[1] == 0 else int(comp.max()) + 1
    if comp.shape[1] and n_actions > comp.shape[0]:
        columns += 1  # the follow action's own column
    planner = PLANNER_CODE[config.planning]
    cap = 0 if planner == ZERO or config.planning_steps == 0 else capacity
    queue = cap if planner == PRIORITIZED else 0
    return Agent(
        np.zeros((coder.size, columns), np.float64) if weights is None else weights,
        coder.spec,
        float(config.gamma),
        float(config.alpha) / touched,
        planner,
        float(config.priority_threshold),
        np.zeros((cap, dims), np.float64),
        np.zeros((cap, dims), np.float64),
        np.zeros(cap, np.int64),
        np.zeros(cap, np.float64),
        np.zeros(cap, np.bool_),
        np.full(cap, -1, np.int64),
        np.zeros(cap, np.bool_),
        np.zeros(queue, np.int64),
        np.zeros(queue, np.float64),
        np.full(queue, -1, np.int64),
        np.zeros(4, np.int64),
        np.zeros(coder.n_active, np.int64),
        np.zeros(coder.n_active, np.int64),
        np.zeros(coder.n_active, np.int64),
        np.zeros(coder.n_active, np.int64),
        np.zeros(n_actions, np.float64),
        comp,
        slots,
        np.zeros(columns if comp.shape[1] else 0, np.float64),
        split,
        pot,
        np.zeros(comp.shape[1], np.float64),
        float(config.alpha) / coder.n_active,
    )


def value_factors(task, coder: TileCoder, pot) -> tuple | None:
    """``(components, slots, split, potential)`` of the factored value when the arm task's
    action set is learned factored (:data:`FACTORED_ACTION_SETS`) on features that tile each
    joint alone, else None (one column per action)."""
    reach = task.reach
    if reach is None or reach.actions not in FACTORED_ACTION_SETS:
        return None
    slots = slot_joints(coder, reach.joints, follows=bool(reach.paths))
    if slots is None:
        return None
    return action_components(reach.directions), slots, reward_split(reach), pot


@dataclass(frozen=True, eq=False)
class LinearResult(ExperimentResult):
    """What :func:`run_experiments` returns for a Gymnasium environment.

    The :class:`ExperimentResult` fields, with ``q`` holding the learned weights, plus:

    Attributes:
        weights: float ``(experiments, size, actions)``: each experiment's weight table
            (the same array as ``q``).
        coder: the bound tile coder (``coder.active(obs)`` gives an observation's features).
        task: the arm task when the environment is ``TeachStudio/ArmReach-v0``, else None.
        env_id: the environment's registered id, when it has one.
        compiled: whether the experiments ran in the compiled kernel (else a Python loop).
    """

    weights: np.ndarray = None  # type: ignore[assignment]
    coder: TileCoder = None  # type: ignore[assignment]
    task: ArmReach | None = None
    env_id: str | None = None
    compiled: bool = False

    def q_values(self, obs: np.ndarray, experiment: int = 0) -> np.ndarray:
        """Q(obs, .) of one experiment's weights, ``(..., actions)``."""
        feats = self.coder.active(obs)
        return self.weights[experiment][feats].sum(axis=-2)


def run_linear_experiments(
    env: str | Callable[[], gymnasium.Env],
    config: DynaQConfig,
    experiments: int,
    episodes: int,
    seed: int,
    demonstrations: Sequence[Sequence[int] | np.ndarray] | None,
    features: TileCoding | None,
    *,
    workers: int | None = None,
    live: LiveProgress | None = None,
    model_capacity: int = DEFAULT_MODEL_CAPACITY,
) -> LinearResult:
    """Linear Dyna-Q on a Gymnasium environment (``run_experiments``'s non-tabular branch).

    Args:
        env: a registered environment id, or a zero-argument callable returning a new
            environment (a lambda is fine: it is called in this process, never pickled), with a
            Box observation space and a Discrete action space.
        config: learning settings (``alpha`` is divided among the active features).
        experiments: independent repetitions.
        episodes: episodes per experiment.
        seed: a non-negative integer.
        demonstrations: replayed as the first episodes: for ``TeachStudio/ArmReach-v0`` joint
            paths ``(N, joints)`` in radians, which also shape every reward with a potential
            read from them (:mod:`._demo_shaping`); for any environment, action sequences
            replayed from ``env.reset``.
        features: the tile coding (required).
        workers: threads for the compiled kernel (default: one per core).
        live: progress arrays to fill and the stop flag to obey.
        model_capacity: transitions the sample model keeps.

    Raises:
        LearningError: bad input, each with one sentence naming it and the fix.
    """
    if not isinstance(features, TileCoding):
        raise LearningError(
            f"features is {type(features).__name__}; give a TileCoding (for example TileCoding(tilings=8, tiles=8)) to learn on a Gymnasium environment."
        )
    if not (isinstance(env, str) or callable(env)):
        raise LearningError(
            f"env is a {type(env).__name__}; give a TabularMDP, a Gymnasium id or a zero-argument callable returning an environment."
        )
    seed, workers, live = check_run_arguments(config, experiments, episodes, seed, workers, live)
    envs = [make_env(env, e) for e in range(experiments)]
    try:
        task = followed_task(envs, config, demonstrations or [])
        if task.reach is not None and task.reach.paths:
            features = with_cost_group(features, task.reach.joints)
        coder = features.bind(task.low, task.high)
        problem = weight_problem(experiments, coder, task.n_actions)
        if problem:
            raise LearningError(problem)
        dims = int(task.low.shape[0])
        demo_starts, demo_actions = env_demonstrations(demonstrations or [], task)
        pot = demo_potential(task.reach, demo_starts, demo_actions, task.state_dims)
        factors = value_factors(task, coder, pot)
        comp = None if factors is None else factors[0]
        columns = task.n_actions if comp is None else int(comp.max()) + 1
        common = task.follows  # a common column, or the factored value's follow column
        columns += common
        learned = np.zeros((experiments, coder.size, columns), np.float64)
        agents = [  # each learns into its row of ``learned``, which checkpoints read as it learns
            _new_agent(coder, task.n_actions, dims, config, model_capacity, learned[e], factors)
            for e in range(experiments)
        ]
        cpu_seconds = np.zeros(experiments)
        runner = _compiled_experiment if task.code is not None else _python_experiment

        def one(e: int) -> None:
            if task.code is not None:  # the compiled kernel holds no GIL: it may yield the CPU
                lower_thread_priority(live.niceness)
            with live.counting_cpu() as spent:
                runner(
                    envs[e], task, agents[e], config, seed, e, demo_starts, demo_actions, pot, live
                )
            cpu_seconds[e] = spent[0]

        def so_far() -> LinearResult:
            weights = learned if comp is None else expand(learned, comp, row_joints(coder))
            weights = without_common(weights) if common and comp is None else weights
            return result_so_far(
                LinearResult, live, cpu_seconds, weights, config, seed,
                weights=weights, coder=coder, task=task.reach, env_id=task.env_id,
                compiled=task.code is not None,
            )  # fmt: skip

        live.snapshot = so_far
        threads = min(workers, experiments) if task.code is not None else 1
        if threads == 1:
            for e in range(experiments):
                one(e)
        else:
            with ThreadPoolExecutor(max_workers=threads, thread_name_prefix="lineardyna") as pool:
                for future in [pool.submit(one, e) for e in range(experiments)]:
                    future.result()
    finally:
        for made in envs:
            made.close()
    return replace(so_far(), stopped=live.stopped and bool(np.any(live.steps < 0)))


def weight_problem(experiments: int, coder: TileCoder, n_actions: int) -> str | None:
    """The sentence refusing a run whose weight tables would not fit in memory, else None."""
    entries = int(experiments) * coder.size * int(n_actions)
    if entries <= MAX_Q_ENTRIES:
        return None
    return f"{experiments} weight tables of {coder.size:,} rows x {n_actions} actions need {entries * 8 / 1e9:.1f} GB; give TileCoding a smaller size or run fewer experiments (at most {MAX_Q_ENTRIES:,} weights in all)."


def _compiled_experiment(env, task, agent, config, seed, e, demo_starts, demo_actions, pot, live):
    episodes = live.steps.shape[1]
    starts = reset_states(env, task, seed, e, episodes)
    dims = starts.shape[1]
    if any(s is None for s in demo_starts):
        raise LearningError(
            "Action-sequence demonstrations start from env.reset; give the arm task joint paths instead."
        )
    offsets = np.concatenate([[0], np.cumsum([len(a) for a in demo_actions])]).astype(np.int64)
    plays = Episodes(
        starts,
        np.ascontiguousarray(np.array(demo_starts, np.float64).reshape(len(demo_starts), dims)),
        np.ascontiguousarray(
            np.concatenate(demo_actions) if demo_actions else np.zeros(0), np.int64
        ),
        offsets,
        np.int64(task.max_steps),
        np.int64(config.planning_steps),
        float(config.epsilon),
        pot,
    )
    _run_compiled(
        np.int64(task.code), task.params, agent, plays, experiment_seed(seed, e),
        live._stop, live.steps[e], live.updates[e],
    )  # fmt: skip


def _python_experiment(env, task, agent, config, seed, e, demo_starts, demo_actions, pot, live):
    """The same experiment as :func:`_run_compiled`, stepping ``env`` from Python.

    ``pot`` is always the empty potential here: joint-path demonstrations, which shape, need the
    arm task's compiled twin."""
    episodes = live.steps.shape[1]
    rng = experiment_seed(seed, e)
    n_active = agent.feats.shape[0]
    feats = np.empty(n_active, np.int64)
    planner = agent.planner
    epsilon = float(config.epsilon)
    for episode in range(episodes):
        if live.stopped:
            break
        n_plan = plan_budget.py_func(planner, int(config.planning_steps), episode)
        obs, _ = env.reset(seed=reset_seed(seed, e) if episode == 0 else None)
        demo = episode < len(demo_actions)
        if demo and demo_starts[episode] is not None:
            obs, _ = env.reset(options={"q": demo_starts[episode]})
        obs = np.asarray(obs, dtype=np.float64).copy()
        limit = len(demo_actions[episode]) if demo else task.max_steps
        active_features(agent.spec, obs, feats)
        steps = updates = 0
        while steps < limit:
            if demo:
                action = int(demo_actions[episode][steps])
            else:
                action, rng = _act(agent, feats, epsilon, rng)
                rng = np.uint64(rng)  # numba hands uint64 back as a Python int
            obs_next, reward, terminated, truncated, _ = env.step(int(action))
            obs_next = np.asarray(obs_next, dtype=np.float64).copy()
            rng, n = _learn(
                agent, obs, feats, int(action), float(reward), bool(terminated), obs_next,
                steps > 0, n_plan, rng,
            )  # fmt: skip
            rng = np.uint64(rng)
            updates += n
            steps += 1
            if terminated or truncated:
                break
            obs = obs_next
            feats[:] = agent.feats_next
        live.steps[e, episode] = steps
        live.updates[e, episode] = updates
