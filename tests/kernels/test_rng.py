"""Counter-based random streams: reproducibility, distinctness, uniformity, independence.

Statistical thresholds: the χ² tests reject at p < 1e-3 (the usual level for this style of test,
as in Mitsuba's chi2 tests); correlation bounds are 5/√n, i.e. 5 standard errors of a sample
correlation of n independent pairs (false-alarm probability ~6e-7). The seeds are fixed, so every
statistical test here is deterministic: it fails only if the generator changes.
"""

from __future__ import annotations

import numpy as np
from chi2 import pearson_1d
from numba import njit

from eyelume.kernels.rng import mix64, next_uniform, stream_start

P_REJECT = 1e-3
M64 = 2**64
GAMMA = 0x9E3779B97F4A7C15
M1, M2 = 0xBF58476D1CE4E5B9, 0x94D049BB133111EB


# --- an independent reference: SplitMix64 in Python integers --------------------------------------


def _mix_ref(z: int) -> int:
    z = ((z ^ (z >> 30)) * M1) % M64
    z = ((z ^ (z >> 27)) * M2) % M64
    return z ^ (z >> 31)


def _stream_ref(seed: int, ray: int, n: int) -> list[float]:
    """The documented stream: SplitMix64 from mix(mix(seed + γ) + ray), u = (z >> 11) 2⁻⁵³."""
    state = _mix_ref((_mix_ref((seed + GAMMA) % M64) + ray) % M64)
    out = []
    for _ in range(n):
        state = (state + GAMMA) % M64
        out.append((_mix_ref(state) >> 11) * 2.0**-53)
    return out


def _unmix_ref(z: int) -> int:
    """Inverse of the SplitMix64 finaliser (it is a bijection of 64-bit words)."""

    def unxorshift(y: int, s: int) -> int:
        x = y
        for _ in range(64 // s + 1):
            x = y ^ (x >> s)
        return x

    z = unxorshift(z, 31)
    z = (z * pow(M2, -1, M64)) % M64
    z = unxorshift(z, 27)
    z = (z * pow(M1, -1, M64)) % M64
    return unxorshift(z, 30)


# --- helpers that step streams inside Numba, as the estimators do --------------------------------


@njit(cache=True)
def _draws(seed, ray, n):
    out = np.empty(n)
    state = stream_start(seed, ray)
    for i in range(n):
        state, out[i] = next_uniform(state)
    return out


@njit(cache=True)
def _first_draws(seed, ray0, n):
    """First uniform of rays ray0, ray0 + 1, …"""
    out = np.empty(n)
    for i in range(n):
        _, out[i] = next_uniform(stream_start(seed, ray0 + i))
    return out


@njit(cache=True)
def _first_draws_over_seeds(seed0, ray, n):
    out = np.empty(n)
    for i in range(n):
        _, out[i] = next_uniform(stream_start(seed0 + i, ray))
    return out


def _lag1(u: np.ndarray) -> float:
    return float(np.corrcoef(u[:-1], u[1:])[0, 1])


def _uniform_chi2_p(u: np.ndarray, bins: int = 100) -> float:
    """χ² p-value of ``u`` against U[0, 1) over ``bins`` equal cells (the one harness)."""
    return pearson_1d(u, np.linspace(0.0, 1.0, bins + 1), np.full(bins, 1.0 / bins))


# --- tests ----------------------------------------------------------------------------------------


def test_splitmix64_reference_values():
    # Published SplitMix64 outputs for state 0 (Vigna's splitmix64.c): the finaliser is right.
    assert int(mix64(np.uint64(GAMMA))) == 0xE220A8397B1DCDAF
    assert int(mix64(np.uint64((2 * GAMMA) % M64))) == 0x6E789E6AA1B965F4
    assert _mix_ref(GAMMA) == 0xE220A8397B1DCDAF  # the reference agrees


def test_stream_matches_reference_and_is_reproducible():
    for seed, ray in ((0, 0), (1, 0), (2005, 123456789), (2**40 + 3, 2**33)):
        a = _draws(seed, ray, 64)
        np.testing.assert_array_equal(a, _draws(seed, ray, 64))  # same key → same numbers
        np.testing.assert_array_equal(a, _stream_ref(seed, ray, 64))  # bit for bit


def test_stream_stepped_from_python_matches_reference():
    # The kernels are plain functions one may call from Python, passing back the state they
    # return. Numba hands the uint64 state back as a Python int, which it types as int64 on the
    # next call when it is below 2**63; the kernels cast to uint64 so the stream does not depend
    # on that. (A state ≥ 2**63 must be passed as np.uint64: Numba cannot fit it in an int64.)
    seed, ray = 2005, 0
    for wrap in (lambda s: s, np.uint64):
        state = stream_start(seed, ray)
        got = []
        for _ in range(16):
            state, u = next_uniform(wrap(state) if state < 2**63 else np.uint64(state))
            got.append(u)
        np.testing.assert_array_equal(got, _stream_ref(seed, ray, 16))


def test_different_keys_give_different_streams():
    firsts = np.array([_draws(1, ray, 4) for ray in range(2000)])
    assert len({tuple(row) for row in firsts}) == len(firsts)
    firsts = np.array([_draws(seed, 5, 4) for seed in range(2000)])
    assert len({tuple(row) for row in firsts}) == len(firsts)
    # neighbouring streams do not overlap (no shifted copies): on a 2⁻⁵³ grid, 2 × 10⁴ values
    # collide by chance with probability ~ (10⁴)²/2⁵³ ≈ 1e-8
    a, b = _draws(1, 0, 10_000), _draws(1, 1, 10_000)
    assert not set(a) & set(b)
    c = _draws(2, 0, 10_000)
    assert not set(a) & set(c)


def test_uniforms_in_half_open_unit_interval():
    u = _draws(3, 0, 1_000_000)
    assert u.min() >= 0.0 and u.max() < 1.0
    # the extremes of the 53-bit grid: states whose next output is all zeros / all ones
    for word, expected in ((0, 0.0), (M64 - 1, 1.0 - 2.0**-53)):
        before = (_unmix_ref(word) - GAMMA) % M64
        assert _mix_ref((before + GAMMA) % M64) == word
        _, u_edge = next_uniform(np.uint64(before))
        assert u_edge == expected
        assert 0.0 <= u_edge < 1.0


def test_single_stream_uniform_and_serially_uncorrelated():
    n = 1_000_000
    u = _draws(20050801, 42, n)
    assert _uniform_chi2_p(u) > P_REJECT
    assert abs(_lag1(u)) < 5.0 / np.sqrt(n)
    # mean and variance of U(0, 1): 1/2 ± 5·(1/√12)/√n, and 1/12 ± 5·√(1/180)/√n
    assert abs(u.mean() - 0.5) < 5.0 * np.sqrt(1.0 / 12.0 / n)
    assert abs(u.var() - 1.0 / 12.0) < 5.0 * np.sqrt(1.0 / 180.0 / n)


def test_first_draws_across_rays_and_seeds_are_independent():
    # Counter-based streams are only safe if consecutive keys give unrelated numbers: ray i and
    # ray i + 1 (and seed s and s + 1) must look like independent uniforms.
    n = 200_000
    for u in (_first_draws(7, 0, n), _first_draws(7, 2**40, n), _first_draws_over_seeds(0, 9, n)):
        assert _uniform_chi2_p(u) > P_REJECT
        assert abs(_lag1(u)) < 5.0 / np.sqrt(n)
    # the first and second draw of the same ray are uncorrelated too
    pairs = np.array([_draws(11, ray, 2) for ray in range(20_000)])
    rho = float(np.corrcoef(pairs[:, 0], pairs[:, 1])[0, 1])
    assert abs(rho) < 5.0 / np.sqrt(len(pairs))
