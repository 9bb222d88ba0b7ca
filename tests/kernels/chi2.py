"""One χ² goodness-of-fit harness for every sampler / pdf pair (after Mitsuba 3's
``src/python/python/chi2.py`` ``ChiSquareTest``).

A sampler maps uniforms to points of a domain; its pdf gives their density (per steradian on the
sphere, per mm² on a disk). The harness histograms n samples over a grid of cells of the domain's
parameter rectangle, integrates the pdf over every cell (Gauss–Legendre, ``ires`` × ``ires``
nodes per cell) to get the expected counts, pools the cells expecting fewer than 5 (so that the
χ² approximation holds) and returns the p-value of Pearson's statistic (``scipy.stats.chi2``,
cells − 1 degrees of freedom; :func:`pearson`, which 1-D tests use directly through
:func:`pearson_1d`). It also reports the integral of the pdf over the domain (1 for a
normalised pdf) and any sample that fell where the pdf integrates to 0.

Domains (parameters (a, b), and dΩ or dA per da db):

* :data:`SPHERE`: a = cos θ ∈ [−1, 1], b = φ ∈ [0, 2π); dΩ = da db;
* :func:`disk` (radius R): a = (r/R)² ∈ [0, 1], b = φ; dA = R²/2 da db.

A density with a jump (a cone's rim) gets a cell edge on it (``a_edges``): Gauss–Legendre on a
cell the jump cuts would err by far more than the counts' noise.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

__all__ = ["Domain", "SPHERE", "disk", "ChiSquareTest", "ChiSquareResult", "pearson", "pearson_1d"]


@dataclass(frozen=True)
class Domain:
    """A domain's parameter rectangle and its maps (see the module docstring)."""

    name: str
    a_range: tuple[float, float]
    to_params: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]  # points (n, d) → a, b
    to_points: Callable[[np.ndarray, np.ndarray], np.ndarray]  # a, b → points (n, d)
    jacobian: float  # measure per da db


def _sphere_params(v: np.ndarray):
    return np.clip(v[:, 2], -1.0, 1.0), np.mod(np.arctan2(v[:, 1], v[:, 0]), 2 * math.pi)


def _sphere_points(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    s = np.sqrt(np.maximum(0.0, 1.0 - a * a))
    return np.stack([s * np.cos(b), s * np.sin(b), a], axis=-1)


SPHERE = Domain("sphere", (-1.0, 1.0), _sphere_params, _sphere_points, 1.0)


def disk(radius: float) -> Domain:
    """The disk of ``radius`` (mm) about the origin of the (x, y) plane."""

    def to_params(p: np.ndarray):
        return (p[:, 0] ** 2 + p[:, 1] ** 2) / radius**2, np.mod(
            np.arctan2(p[:, 1], p[:, 0]), 2 * math.pi
        )

    def to_points(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        r = radius * np.sqrt(a)
        return np.stack([r * np.cos(b), r * np.sin(b)], axis=-1)

    return Domain(f"disk(R={radius})", (0.0, 1.0), to_params, to_points, radius**2 / 2.0)


def pearson(observed: np.ndarray, expected: np.ndarray) -> tuple[float, float, int]:
    """Pearson's χ² of counts against expected counts (any shape, same shape): the cells
    expecting fewer than 5 pooled into one, cells expecting 0 left out; (p-value, statistic,
    degrees of freedom = cells − 1)."""
    obs, exp = np.asarray(observed, float).ravel(), np.asarray(expected, float).ravel()
    low = exp < 5.0
    if low.any():
        obs = np.append(obs[~low], obs[low].sum())
        exp = np.append(exp[~low], exp[low].sum())
    keep = exp > 0.0
    obs, exp = obs[keep], exp[keep]
    stat = float(((obs - exp) ** 2 / exp).sum())
    dof = obs.size - 1
    return float(stats.chi2.sf(stat, dof)), stat, dof


def pearson_1d(samples: np.ndarray, edges: np.ndarray, probs: np.ndarray) -> float:
    """p-value of 1-D ``samples`` histogrammed over ``edges`` against the cells' probabilities
    ``probs`` (summing to 1: every sample falls in a cell), by :func:`pearson`."""
    observed, _ = np.histogram(samples, bins=edges)
    assert observed.sum() == len(samples), "samples outside the cells"
    assert abs(float(np.sum(probs)) - 1.0) < 1e-9, float(np.sum(probs))
    return pearson(observed, np.asarray(probs) * len(samples))[0]


@dataclass
class ChiSquareResult:
    p_value: float
    statistic: float
    dof: int
    pdf_integral: float  # ∫ pdf over the domain (1 when normalised)
    impossible: int  # samples in cells where the pdf integrates to 0
    observed: np.ndarray = field(repr=False)
    expected: np.ndarray = field(repr=False)


@dataclass
class ChiSquareTest:
    """``sample(n)`` → (n, d) points; ``pdf(points)`` → (m,) densities. See module docstring."""

    domain: Domain
    sample: Callable[[int], np.ndarray]
    pdf: Callable[[np.ndarray], np.ndarray]
    sample_count: int = 500_000
    res: tuple[int, int] = (20, 40)
    ires: int = 6
    a_edges: tuple[float, ...] = ()  # extra cell edges in a (jumps of the density)

    def edges(self) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = self.domain.a_range
        a = np.union1d(np.linspace(lo, hi, self.res[0] + 1), np.asarray(self.a_edges, float))
        return a, np.linspace(0.0, 2 * math.pi, self.res[1] + 1)

    def expected_probabilities(self) -> np.ndarray:
        """∫ pdf over each cell (a cells × b cells), by Gauss–Legendre."""
        a_edges, b_edges = self.edges()
        g, w = np.polynomial.legendre.leggauss(self.ires)

        def nodes(edges):
            lo, hi = edges[:-1, None], edges[1:, None]
            return 0.5 * (lo + hi) + 0.5 * (hi - lo) * g, 0.5 * (hi - lo) * w

        an, aw = nodes(a_edges)  # (na, ires)
        bn, bw = nodes(b_edges)  # (nb, ires)
        A = np.broadcast_to(an[:, None, :, None], (an.shape[0], bn.shape[0], self.ires, self.ires))
        B = np.broadcast_to(bn[None, :, None, :], A.shape)
        dens = np.asarray(self.pdf(self.domain.to_points(A.ravel(), B.ravel())), float)
        dens = dens.reshape(A.shape)
        weights = aw[:, None, :, None] * bw[None, :, None, :]
        return (dens * weights).sum(axis=(2, 3)) * self.domain.jacobian

    def run(self) -> ChiSquareResult:
        a_edges, b_edges = self.edges()
        pts = np.asarray(self.sample(self.sample_count), float)
        a, b = self.domain.to_params(pts)
        observed, _, _ = np.histogram2d(a, b, bins=(a_edges, b_edges))
        probs = self.expected_probabilities()
        integral = float(probs.sum())
        impossible = int(observed[probs <= 0.0].sum())
        p_value, stat, dof = pearson(observed, probs * self.sample_count)
        return ChiSquareResult(p_value, stat, dof, integral, impossible, observed, probs)
