"""Counter-based random streams: every ray's numbers depend on (seed, ray index) alone.

Each function casts its state to uint64 first: a state handed back to them from Python is a
plain int, which Numba types as int64, and the arithmetic must stay unsigned. (Pass states from
Python as ``np.uint64``: a plain int ≥ 2**63 cannot enter an int64 specialisation.)

A ray's stream is the SplitMix64 sequence (Steele, Lea & Flood, OOPSLA 2014) started from
``hash64(hash64(seed) + ray_index)``, so a result never depends on thread count or batch size.
"""

from __future__ import annotations

import numpy as np
from numba import njit

_GAMMA = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30 = np.uint64(30)
_S27 = np.uint64(27)
_S31 = np.uint64(31)
_S11 = np.uint64(11)
_INV53 = 1.0 / 9007199254740992.0  # 2**-53


@njit(cache=True, inline="always")
def mix64(z):
    """The SplitMix64 finaliser: a bijective 64-bit hash (uint64 → uint64)."""
    z = np.uint64(z)
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


@njit(cache=True, inline="always")
def stream_start(seed, ray_index):
    """Initial state of the stream of ray ``ray_index`` under ``seed`` (both non-negative ints)."""
    return mix64(mix64(np.uint64(seed) + _GAMMA) + np.uint64(ray_index))


@njit(cache=True, inline="always")
def next_uniform(state):
    """Advance a stream: returns (new_state, u) with u uniform in [0, 1) on a 2**-53 grid."""
    state = np.uint64(state) + _GAMMA
    return state, float(mix64(state) >> _S11) * _INV53


@njit(cache=True, inline="always")
def side_uniform(state, tag):
    """A uniform in [0, 1) drawn beside a stream without advancing it: from the hash of its
    state and a ``tag`` (a constant per use), so the stream's own numbers stay as they were."""
    return float(mix64(np.uint64(state) ^ np.uint64(tag)) >> _S11) * _INV53
