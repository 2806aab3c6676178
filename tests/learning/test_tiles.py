"""Tile coding laws: one feature per tiling, indices within size, nearby observations share tiles."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.learning import LearningError, TileCoding
from studio.learning._tiles import active_features

LOW = np.array([-1.2, -0.07, 0.0])
HIGH = np.array([0.6, 0.07, 10.0])

unit_obs = st.lists(st.floats(0.0, 1.0), min_size=3, max_size=3).map(
    lambda u: LOW + np.array(u) * (HIGH - LOW)
)
codings = st.builds(
    TileCoding,
    tilings=st.sampled_from([1, 2, 4, 8, 16]),
    tiles=st.integers(1, 20),
    size=st.one_of(st.none(), st.integers(1, 5000)),
)


@settings(max_examples=60, deadline=None)
@given(codings, st.lists(unit_obs, min_size=1, max_size=5))
def test_one_active_feature_per_tiling_within_size_and_numba_agrees(coding, obs):
    coder = coding.bind(LOW, HIGH)
    feats = coder.active(np.array(obs))
    assert feats.shape == (len(obs), coding.tilings) == (len(obs), coder.n_active)
    assert feats.min() >= 0 and feats.max() < coder.size
    out = np.empty(coder.n_active, np.int64)
    for x, expected in zip(obs, feats, strict=True):
        active_features(coder.spec, np.asarray(x, dtype=np.float64), out)
        assert np.array_equal(out, expected)
    if not coder.hashed:  # without hashing, each tiling owns its own block of indices
        per_tiling = (coding.tiles + 1) ** 3
        assert np.array_equal(
            feats // per_tiling, np.tile(np.arange(coding.tilings), (len(obs), 1))
        )


@settings(max_examples=80, deadline=None)
@given(unit_obs, st.lists(st.floats(-0.02, 0.02), min_size=3, max_size=3))
def test_nearby_observations_share_most_features(x, fraction):
    """Two observations differ in at most sum_d ceil(|du_d| * tilings) tilings (du in tiles)."""
    coder = TileCoding(tilings=8, tiles=8).bind(LOW, HIGH)
    y = np.clip(x + np.array(fraction) * (HIGH - LOW), LOW, HIGH)
    a, b = coder.active(x), coder.active(y)
    du = np.abs(y - x) * 8 / (HIGH - LOW)
    bound = sum(max(math.ceil(d * 8 - 1e-9), int(d > 0)) for d in du)  # any move may cross one
    assert int(np.sum(a != b)) <= bound
    assert np.array_equal(coder.active(x), a)  # the same observation, the same tiles


def test_far_apart_observations_share_nothing_and_bounds_clip():
    coder = TileCoding(tilings=8, tiles=8).bind(LOW, HIGH)
    assert not set(coder.active(LOW)) & set(coder.active(HIGH))
    assert np.array_equal(coder.active(HIGH + 5.0), coder.active(HIGH))  # outside clips in


def test_groups_tile_each_subset_and_hashing_keeps_the_table_small():
    coder = TileCoding(tilings=4, tiles=10, groups=((0,), (1, 2))).bind(LOW, HIGH)
    assert coder.n_active == 8 and not coder.hashed
    assert coder.size == 4 * 11 + 4 * 11**2
    x = np.array([0.0, 0.0, 5.0])
    moved = x.copy()
    moved[0] = 0.5  # only the first group's tiles change
    assert np.array_equal(coder.active(x)[4:], coder.active(moved)[4:])
    assert not np.array_equal(coder.active(x)[:4], coder.active(moved)[:4])
    big = TileCoding(tilings=8, tiles=100).bind(np.zeros(6), np.ones(6))
    assert big.hashed and big.size == 1 << 20 and big.plain_count > 10**12
    feats = big.active(np.random.default_rng(0).random((200, 6)))
    assert feats.min() >= 0 and feats.max() < big.size


def test_bad_settings_one_sentence_each():
    with pytest.raises(LearningError, match="tilings is 0"):
        TileCoding(tilings=0)
    with pytest.raises(LearningError, match="tiles is 0"):
        TileCoding(tiles=0)
    with pytest.raises(LearningError, match="size"):
        TileCoding(size=0)
    with pytest.raises(LearningError, match=r"unbounded in dimension\(s\) \[1\]"):
        TileCoding().bind([0.0, -np.inf], [1.0, np.inf])
    with pytest.raises(LearningError, match="empty"):
        TileCoding().bind([0.0], [0.0])
    with pytest.raises(LearningError, match="groups name"):
        TileCoding(groups=((0, 3),)).bind([0.0, 0.0], [1.0, 1.0])
    # explicit bounds make an unbounded box usable
    coder = TileCoding(low=(0.0, -1.0), high=(1.0, 1.0)).bind([0.0, -np.inf], [1.0, np.inf])
    assert coder.active([0.5, 0.0]).shape == (8,)
