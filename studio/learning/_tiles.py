"""Tile coding: binary features over a box of observations (Sutton & Barto, section 9.5.4).

``TileCoding(tilings=8, tiles=8)`` lays ``tilings`` grids over the observation box, each with
``tiles`` tiles per dimension, each grid shifted from the first by a fraction of a tile. An
observation activates exactly one tile per tiling, so a linear function of the features is the sum
of ``tilings`` weights, and two nearby observations share most of their tiles (that is the
generalisation).

Coordinates. Dimension ``d`` is scaled to ``u_d = (clip(x_d, low_d, high_d) - low_d) * tiles /
(high_d - low_d)`` (so ``u_d`` is in ``[0, tiles]``). Tiling ``t`` shifts dimension ``d`` by the
fraction ``((t * (2 d + 1)) mod tilings) / tilings`` of a tile, the odd displacement vectors
Sutton & Barto recommend (uniform displacements line every tiling up along the diagonal), and its
tile coordinate is ``c_d = floor(u_d + shift)``, an integer in ``[0, tiles]``: ``tiles + 1``
positions, because a shifted grid needs one more tile to cover the box.

Indices. With ``groups`` (default: one group of every dimension), each group has its own
``tilings`` tilings over its dimensions only (Sutton & Barto's "tilings over subsets"), so the
active features number ``tilings x len(groups)``. A tile's plain index is ``base + t * per_tiling
+ sum_d c_d * (tiles + 1) ** rank_d``, numbering every tile of every tiling of every group apart.
When that count fits in ``size`` the plain index is the feature (no collisions); otherwise it is
hashed with splitmix64's mixer and reduced modulo ``size`` (a fixed-size table whatever the
dimension, at the price of rare collisions).

Two implementations compute the same integers: :meth:`TileCoder.active` (numpy, vectorised over
many observations) and :func:`active_features` (numba, for the learners' kernels); a test holds
them equal.
"""

from __future__ import annotations

from collections import namedtuple
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numba import njit

from .._numbers import is_int
from ._errors import ConfigError, LearningError

DEFAULT_TILINGS = 8
"""Offset tilings (Sutton & Barto's Mountain Car uses 8)."""
DEFAULT_TILES = 8
"""Tiles per dimension over the observation's bounds in each tiling (Sutton & Barto: 8)."""
DEFAULT_MAX_SIZE = 1 << 20
"""Weight rows when ``size`` is not given and the plain tile count is larger: hashed into 2**20."""
MAX_SIZE = 1 << 28
"""Largest weight table (rows) a tile coder may ask for; runs also bound rows x actions."""
MAX_TILINGS = 1024
"""Upper bound on tilings per group (beyond it every step costs microseconds)."""
MAX_TILES = 1 << 16
"""Upper bound on tiles per dimension."""

_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_U27 = np.uint64(27)
_U30 = np.uint64(30)
_U31 = np.uint64(31)

TileSpec = namedtuple("TileSpec", "low high scale shifts strides bases hashed size")
"""The numbers :func:`active_features` needs, as arrays a numba kernel accepts.

``low (D,)``, ``high (D,)`` and ``scale (D,)`` map an observation to tile units; ``shifts (T, D)`` is each
tiling's shift; ``strides (G, D)`` holds ``(tiles + 1) ** rank`` for the group's dimensions and 0
for the others; ``bases (G, T)`` each tiling's first plain index; ``hashed`` whether indices are
hashed; ``size`` the number of weight rows.
"""


@dataclass(frozen=True)
class TileCoding:
    """Tile-coding settings; :meth:`bind` turns them into a :class:`TileCoder` for a box.

    Attributes:
        tilings: offset tilings (per group); the number of active features per group.
        tiles: tiles per dimension over the observation's bounds, in each tiling.
        size: weight rows; default: the plain tile count when it is at most
            :data:`DEFAULT_MAX_SIZE`, else :data:`DEFAULT_MAX_SIZE` (hashed).
        low: explicit lower bounds, one per dimension (needed where the space's are infinite).
        high: explicit upper bounds.
        groups: dimension subsets each tiled on its own (default: all dimensions together). For
            example ``((0,), (1,), (2,))`` tiles each joint alone: the features then represent
            sums of per-dimension functions, with far fewer tiles than one joint grid.

    Raises:
        LearningError: for a bad value (one sentence naming it and the fix).
    """

    tilings: int = DEFAULT_TILINGS
    tiles: int = DEFAULT_TILES
    size: int | None = None
    low: tuple[float, ...] | None = None
    high: tuple[float, ...] | None = None
    groups: tuple[tuple[int, ...], ...] | None = None

    def __post_init__(self) -> None:
        for name, high in (("tilings", MAX_TILINGS), ("tiles", MAX_TILES)):
            value = getattr(self, name)
            if not is_int(value) or not 1 <= value <= high:
                raise ConfigError(
                    [
                        f"{name} is {value!r}; give a whole number from 1 to {high:,} ({name} of zero would activate no feature)."
                    ],
                    [name],
                )
            object.__setattr__(self, name, int(value))
        if self.size is not None:
            if not is_int(self.size) or not 1 <= self.size <= MAX_SIZE:
                raise ConfigError(
                    [
                        f"size is {self.size!r}; give a whole number of weight rows from 1 to {MAX_SIZE:,}."
                    ],
                    ["size"],
                )
            object.__setattr__(self, "size", int(self.size))
        for name in ("low", "high"):
            value = getattr(self, name)
            if value is None:
                continue
            arr = np.asarray(value, dtype=np.float64).reshape(-1)
            if not np.all(np.isfinite(arr)):
                raise LearningError(f"{name} is {value!r}; give finite bounds, one per dimension.")
            object.__setattr__(self, name, tuple(float(x) for x in arr))
        if self.groups is not None:
            try:
                groups = tuple(tuple(int(d) for d in g) for g in self.groups)
            except (TypeError, ValueError):
                raise LearningError(
                    f"groups is {self.groups!r}; give tuples of dimension indices, for example ((0,), (1,))."
                ) from None
            if not groups or any(not g or len(set(g)) != len(g) for g in groups):
                raise LearningError(
                    f"groups is {self.groups!r}; give non-empty groups without repeated dimensions."
                )
            object.__setattr__(self, "groups", groups)

    def to_dict(self) -> dict:
        """The settings as JSON-ready values (the inverse of ``TileCoding(**d)``)."""
        return {
            "tilings": self.tilings,
            "tiles": self.tiles,
            "size": self.size,
            "low": None if self.low is None else list(self.low),
            "high": None if self.high is None else list(self.high),
            "groups": None if self.groups is None else [list(g) for g in self.groups],
        }

    @classmethod
    def from_dict(cls, data: dict) -> TileCoding:
        """Settings from :meth:`to_dict`'s form."""
        groups = data.get("groups")
        return cls(
            tilings=data["tilings"],
            tiles=data["tiles"],
            size=data.get("size"),
            low=None if data.get("low") is None else tuple(data["low"]),
            high=None if data.get("high") is None else tuple(data["high"]),
            groups=None if groups is None else tuple(tuple(g) for g in groups),
        )

    def bind(
        self, low: Sequence[float] | np.ndarray, high: Sequence[float] | np.ndarray
    ) -> TileCoder:
        """The tile coder for a box (explicit ``self.low``/``self.high`` take precedence).

        Args:
            low: the observation space's lower bounds, shape ``(D,)``.
            high: its upper bounds.

        Raises:
            LearningError: infinite bounds with no explicit ones, groups naming a missing
                dimension, or an empty box.
        """
        space_low = np.asarray(low, dtype=np.float64).reshape(-1)
        space_high = np.asarray(high, dtype=np.float64).reshape(-1)
        if space_low.shape != space_high.shape:
            raise LearningError(
                f"The box bounds have shapes {space_low.shape} and {space_high.shape}; give one low and one high per dimension."
            )
        dims = space_low.shape[0]
        lo = space_low if self.low is None else np.asarray(self.low)
        hi = space_high if self.high is None else np.asarray(self.high)
        if lo.shape != (dims,) or hi.shape != (dims,):
            raise LearningError(
                f"TileCoding low/high have {lo.shape[0]} and {hi.shape[0]} values but the observation has {dims} dimensions; give one bound per dimension."
            )
        if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            bad = [d for d in range(dims) if not (np.isfinite(lo[d]) and np.isfinite(hi[d]))]
            raise LearningError(
                f"The observation box is unbounded in dimension(s) {bad}, so tiles cannot span it; give TileCoding(low=..., high=...) with finite bounds."
            )
        if not np.all(lo < hi):
            raise LearningError(
                f"The tile-coding box [{lo.tolist()}, {hi.tolist()}] is empty in some dimension; give low below high."
            )
        groups = self.groups if self.groups is not None else (tuple(range(dims)),)
        for g in groups:
            if min(g) < 0 or max(g) >= dims:
                raise LearningError(
                    f"groups name dimension(s) {list(g)} but the observation has {dims} (0 to {dims - 1}); give dimensions that exist."
                )
        return TileCoder(self, lo.astype(np.float64), hi.astype(np.float64), groups)


class TileCoder:
    """A :class:`TileCoding` bound to a box: computes active features.

    Attributes:
        coding: the settings.
        low: lower bounds used, ``(D,)``.
        high: upper bounds used, ``(D,)``.
        groups: the dimension groups used.
        plain_count: tiles over all tilings and groups (the table size without hashing).
        size: weight rows.
        hashed: whether indices are hashed into ``size`` rows.
        n_active: active features per observation (``tilings x len(groups)``).
    """

    def __init__(
        self,
        coding: TileCoding,
        low: np.ndarray,
        high: np.ndarray,
        groups: tuple[tuple[int, ...], ...],
    ) -> None:
        self.coding = coding
        self.low = low
        self.high = high
        self.groups = groups
        n = coding.tilings
        width = coding.tiles + 1
        per_tiling = [width ** len(g) for g in groups]
        self.plain_count = int(n * sum(per_tiling))
        if coding.size is not None:
            self.size = coding.size
        else:
            self.size = min(self.plain_count, DEFAULT_MAX_SIZE)
        self.hashed = self.plain_count > self.size
        self.n_active = n * len(groups)
        dims = low.shape[0]
        self._scale = coding.tiles / (high - low)
        t = np.arange(n)[:, None]
        d = np.arange(dims)[None, :]
        self._shifts = ((t * (2 * d + 1)) % n) / n  # (T, D)
        self._strides = np.zeros((len(groups), dims), np.uint64)
        self._bases = np.zeros((len(groups), n), np.uint64)
        base = 0
        for gi, g in enumerate(groups):
            for rank, dim in enumerate(g):
                self._strides[gi, dim] = width**rank
            self._bases[gi] = base + np.arange(n, dtype=np.uint64) * np.uint64(per_tiling[gi])
            base += n * per_tiling[gi]

    @property
    def dims(self) -> int:
        """Observation dimensions."""
        return int(self.low.shape[0])

    @cached_property
    def spec(self) -> TileSpec:
        """The arrays :func:`active_features` takes."""
        return TileSpec(
            np.ascontiguousarray(self.low),
            np.ascontiguousarray(self.high),
            np.ascontiguousarray(self._scale),
            np.ascontiguousarray(self._shifts),
            np.ascontiguousarray(self._strides),
            np.ascontiguousarray(self._bases),
            bool(self.hashed),
            np.int64(self.size),
        )

    def active(self, obs: Sequence[float] | np.ndarray) -> np.ndarray:
        """Active feature indices, ``(..., n_active)`` int64, for observations ``(..., D)``.

        Raises:
            LearningError: wrong last dimension or non-finite values.
        """
        x = np.asarray(obs, dtype=np.float64)
        if x.shape[-1:] != (self.dims,):
            raise LearningError(
                f"The observations have shape {x.shape}; give {self.dims} values per observation."
            )
        if not np.all(np.isfinite(x)):
            raise LearningError("The observations hold NaN or infinite values; give finite ones.")
        u = (np.clip(x, self.low, self.high) - self.low) * self._scale  # (..., D)
        coords = np.floor(u[..., None, :] + self._shifts).astype(np.uint64)  # (..., T, D)
        plain = self._bases + np.einsum(
            "...td,gd->...gt", coords, self._strides, dtype=np.uint64
        )  # (..., G, T)
        plain = plain.reshape(*x.shape[:-1], self.n_active)
        if not self.hashed:
            return plain.astype(np.int64)
        return (_mix_np(plain) % np.uint64(self.size)).astype(np.int64)

    def table_bytes(self, n_actions: int) -> int:
        """Bytes of one float64 weight table of ``size`` rows by ``n_actions`` columns."""
        return int(self.size) * int(n_actions) * 8


def _mix_np(z: np.ndarray) -> np.ndarray:
    """splitmix64's mixer on uint64 arrays (wrapping arithmetic), as :func:`_mix_index`."""
    with np.errstate(over="ignore"):
        z = z + _GOLDEN
        z = (z ^ (z >> _U30)) * _MIX1
        z = (z ^ (z >> _U27)) * _MIX2
        return z ^ (z >> _U31)


@njit(nogil=True, cache=True, inline="always")
def _mix_index(z):
    """splitmix64's mixer on one plain tile index (as :func:`_mix_np`)."""
    z = z + _GOLDEN
    z = (z ^ (z >> _U30)) * _MIX1
    z = (z ^ (z >> _U27)) * _MIX2
    return z ^ (z >> _U31)


@njit(nogil=True, cache=True)
def active_features(spec, obs, out):
    """Write the active feature indices of one observation into ``out`` (int64, ``(T x G,)``).

    The compiled twin of :meth:`TileCoder.active` (same integers), for use inside kernels:
    ``spec`` is :attr:`TileCoder.spec`, ``obs`` a float64 ``(D,)`` array.
    """
    low = spec.low
    high = spec.high
    scale = spec.scale
    shifts = spec.shifts
    strides = spec.strides
    bases = spec.bases
    n_tilings, dims = shifts.shape
    n_groups = strides.shape[0]
    size = np.uint64(spec.size)
    k = 0
    for g in range(n_groups):
        for t in range(n_tilings):
            plain = bases[g, t]
            for d in range(dims):
                stride = strides[g, d]
                if stride == 0:
                    continue
                lo = low[d]
                u = (min(max(obs[d], lo), high[d]) - lo) * scale[d]
                plain += np.uint64(np.floor(u + shifts[t, d])) * stride
            if spec.hashed:
                out[k] = np.int64(_mix_index(plain) % size)
            else:
                out[k] = np.int64(plain)
            k += 1
