"""The named data the kernels read: NamedTuples of arrays and scalars, built once per scene by
:mod:`eyelume.compile` and handed to a kernel as one argument each.

Numba compiles a ``typing.NamedTuple`` of arrays and scalars as a struct (arguments and return
values, under ``cache=True`` and ``prange``), so a kernel takes ``(surfaces, leds, camera, …)``
instead of twenty positional arrays, and the call sites do not repeat the list. Arrays are
C-contiguous float64 / int64; world millimetres throughout.

* :class:`SurfaceTable` — the non-sequential surfaces (columns in :mod:`.geometry`);
* :class:`LensTable` — the imaging lens, traced sequentially (columns in :mod:`.sequential`);
* :class:`LedTable` — the LEDs' emission points, axes, I₀ and angular-profile tables;
* :class:`CameraTables` — the lens seen backwards from the sensor, its pupils and the aim table
  of the camera-side estimator;
* :class:`eyelume.kernels.bins.PlaneGrid` — the picture and the eye-plane receiver's bins;
* :class:`SceneTables` — all of the above that a forward trace reads, in one struct.

A ``prange`` body takes arrays, scalars and flat NamedTuples of them, but not a NamedTuple of
NamedTuples (numba#10139: "scalar type … given for non scalar argument"), nor a NamedTuple made
outside the loop in the same function. So a parallel kernel takes :func:`scene_parts` as
separate arguments (its public, serial wrapper passes them) and rebuilds ``SceneTables(*parts)``
inside its loop: no copy, the arrays are shared.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from eyelume.kernels.bins import PlaneGrid

__all__ = [
    "Ray",
    "Facet",
    "SurfaceTable",
    "LensTable",
    "LedTable",
    "CameraTables",
    "SceneTables",
    "scene_parts",
    "A_X",
    "A_Y",
    "A_Z",
    "A_R",
    "A_P",
    "A_KIND",
    "A_AX",
    "A_AY",
    "A_AZ",
    "AIM_DISK",
    "AIM_IMAGE",
    "N_AIM",
    "TRANSMIT_A",
    "TRANSMIT",
    "REFLECT",
    "CHAIN_STEPS",
    "CHAIN_COLS",
    "G_AX",
    "G_AY",
    "G_AZ",
    "G_COS",
    "G_P",
    "GLINT_AIM_COLS",
]

# aim table columns: centre xyz, radius (mm), probability of aiming, kind, and for AIM_IMAGE
# an axis: AIM_DISK aims at a disk (its normal world +z: the entrance pupil seen straight);
# AIM_IMAGE at the entrance pupil's image through optical elements, a sphere about the centre,
# the axis the camera's line of sight leaves the elements along (kernels/sampling.py)
A_X, A_Y, A_Z, A_R, A_P, A_KIND, A_AX, A_AY, A_AZ = range(9)
N_AIM = 9
AIM_DISK, AIM_IMAGE = 0, 1

#: A specular chain's step (CameraTables.chains): transmitted arriving from side A only (the
#: cornea, entered from outside), transmitted from either side, or reflected.
TRANSMIT_A, TRANSMIT, REFLECT = 0, 1, 2
#: Most steps of a chain (an element's two surfaces, then the cornea's two), and the columns of
#: a chain row: the steps toward any face (0: none), the steps toward a face seen through the
#: cornea (the iris), then CHAIN_STEPS surface rows and CHAIN_STEPS modes.
CHAIN_STEPS = 4
CHAIN_COLS = 2 + 2 * CHAIN_STEPS


#: The columns of ``CameraTables.indirect`` (x, y, z, nx, ny, nz, value, surface, variance,
#: reach).
INDIRECT_COLS = 10


#: The least continuation grid on the surfaces lit through the cornea (the iris) when the scene
#: gives none (``run.iris_continuation_grid`` None): :mod:`eyelume.compile` sets
#: ``CameraTables.iris_grid`` to max(``run.continuation_grid``, this), and the fast estimator's
#: branches followed in one direction take it on the iris (why 3: the comment above
#: ``_path_radiance`` in :mod:`eyelume.estimators.fast`).
IRIS_GRID = 3


class Ray(NamedTuple):
    """A ray: origin (x, y, z) and unit direction (dx, dy, dz), world mm."""

    x: float
    y: float
    z: float
    dx: float
    dy: float
    dz: float


class Facet(NamedTuple):
    """A point on a face (x, y, z) and its unit normal (nx, ny, nz) toward the light's side,
    world mm."""

    x: float
    y: float
    z: float
    nx: float
    ny: float
    nz: float


class SurfaceTable(NamedTuple):
    """Non-sequential surfaces (eye, iris, sclera, retina, face tissues, LED bodies, the lens's
    entrance): ``sf`` (n, N_FLOAT) float64 and ``si`` (n, N_INT) int64, columns in
    :mod:`eyelume.kernels.geometry`."""

    sf: np.ndarray
    si: np.ndarray


class LensTable(NamedTuple):
    """The imaging lens: ``lf`` (n_lens, N_LENS_COL) float64, one row per surface in order
    (columns in :mod:`eyelume.kernels.sequential`), and the world z (mm) of the image plane."""

    lf: np.ndarray
    image_z: float


class LedTable(NamedTuple):
    """The LEDs as point sources, each with its own I₀ and angular profile.

    ``points`` (N, 3) emission points (world mm, on the body's front), ``axes`` (N, 3) unit
    axes, ``i0`` (N,) the on-axis radiant intensities I₀ (W/sr), and each LED's profile on the
    uniform grid ``alpha_grid`` (n,) (rad, [0, π/2]): ``cdf_grid`` (N, n) the normalised
    ∫₀^α I sin α' dα' (for sampling), ``intensity_grid`` (N, n) I(α)/I₀ (for evaluating,
    :func:`eyelume.kernels.sampling.radiant_intensity`). ``power_cdf`` (N,) the cumulative
    share of the emitted power Φₖ = I₀ₖ Ω_eff,k (the last 1), by which a forward ray picks its
    LED; ``equal_power`` True when every LED emits the same power (then LED ⌊u N⌋)."""

    points: np.ndarray
    axes: np.ndarray
    i0: np.ndarray
    alpha_grid: np.ndarray
    cdf_grid: np.ndarray
    intensity_grid: np.ndarray
    power_cdf: np.ndarray
    equal_power: bool


#: Columns of :attr:`CameraTables.glint_aim`: the cone's unit axis, cos of its half-angle, the
#: share of draws aimed in it.
G_AX, G_AY, G_AZ, G_COS, G_P = range(5)
GLINT_AIM_COLS = 5


class CameraTables(NamedTuple):
    """The camera as the camera-side (fast) estimator sees it (:mod:`eyelume.estimators.camera`).

    ``lf_rev``: the lens table mirrored through z = 0 and reversed (trace from the sensor out);
    ``lf_open``: the same with open apertures (for aiming); ``k_stop``: the stop's row in
    ``lf_rev``; ``stop_radius`` (mm); ``image_z``, ``rear_z`` (world z of the sensor and of the
    last lens vertex); ``exit_pupil_z``, ``exit_pupil_magnification`` (paraxial exit pupil);
    ``entrance_pupil_z``; ``aim`` (n_surfaces, 2, N_AIM): per Lambertian face and side (0 = A,
    1 = B) the disk (or the pupil's image through elements, ``A_KIND``) to aim scattered light
    at and the probability of aiming;
    ``through_cornea`` (n_surfaces,) int64: 1 where next-event estimation goes through the
    cornea (the iris); ``cornea``: the surface index of the anterior cornea (``cornea + 1`` is
    the posterior one); ``split_grid``: a camera path continues from its first Lambertian
    vertex in split_grid² stratified directions (``run.continuation_grid``), in iris_grid²
    on the surfaces lit through the cornea (``run.iris_continuation_grid``; by default
    ``run.continuation_grid`` but at least :data:`IRIS_GRID`, 3).

    Optical elements (issue 14): ``element_rows`` (m,) int64 the rows of their optical
    surfaces (increasing; elements come last in the surface table), each the start of a light
    path leg; ``chains`` (n_leds, n_chains, CHAIN_COLS) int64: per LED, the specular chains
    through one element that next-event estimation connects by Newton's method
    (:mod:`eyelume.estimators.cornea_nee`): an element's first step is the surface the LED
    faces, its own chain toward any face and, with the cornea's two steps appended, toward the
    iris; ``n_chains`` 0 without elements.

    ``glint_aim`` (n_leds, GLINT_AIM_COLS) float64: per LED the cone its light paths aim at
    the cornea's specular point for the camera (the glint): unit axis (camera frame), cos of
    its half-angle, and the share of the LED's cornea-leg draws aimed in it (0: none, every
    draw in the cone that holds the cornea; :mod:`eyelume.estimators.fast`).

    ``dark_from``: the first row of the surface table's dark tail
    (:func:`eyelume.kernels.geometry.dark_tail`: the LED packages, the camera's body and lens
    entrance when they come last), which a camera path searches only behind a lit row it meets
    (:func:`eyelume.kernels.geometry.nearest_lit_hit`); the row count when there is none.

    ``indirect`` (ny, nx, INDIRECT_COLS) float64: the irradiance cache of ``run.indirect =
    "cache"`` (:func:`eyelume.estimators.fast.indirect_cache`), a point every
    ``indirect_spacing`` pixels of the picture (rows and columns, from its corner): the first
    Lambertian vertex of the pixel point's chief ray (x, y, z, its normal toward the camera's
    side), its indirect radiance per unit throughput (W/(mm²·sr)), the surface row (−1: none,
    or a surface lit through the cornea, which keeps its paths), the cache estimate's variance
    and its reach (mm): the farthest a vertex may lie from it to read it
    (:func:`eyelume.estimators.fast_run.with_indirect_cache`); ``indirect_tol`` (mm) the
    median reach.
    (0, 0, INDIRECT_COLS) and spacing 0: no cache, every first vertex continues by paths."""

    lf_rev: np.ndarray
    lf_open: np.ndarray
    k_stop: int
    stop_radius: float
    image_z: float
    rear_z: float
    exit_pupil_z: float
    exit_pupil_magnification: float
    entrance_pupil_z: float
    aim: np.ndarray
    through_cornea: np.ndarray
    cornea: int
    split_grid: int
    iris_grid: int
    element_rows: np.ndarray
    chains: np.ndarray
    glint_aim: np.ndarray
    dark_from: int
    indirect: np.ndarray
    indirect_spacing: float
    indirect_tol: float


class SceneTables(NamedTuple):
    """What a forward trace reads: surfaces, lens, LEDs, the picture grid on the sensor, the
    eye-plane receiver's grid and the per-ray event limit."""

    surfaces: SurfaceTable
    lens: LensTable
    leds: LedTable
    picture: PlaneGrid
    eye_plane: PlaneGrid
    max_events: int


@njit(cache=True, inline="always")
def scene_parts(scene):
    """The fields of a :class:`SceneTables` as a plain tuple (surfaces, lens, leds, picture,
    eye_plane, max_events), to hand to a parallel kernel as separate arguments (``*parts``; see
    the module docstring); ``SceneTables(*parts)`` rebuilds it."""
    return (
        scene.surfaces,
        scene.lens,
        scene.leds,
        scene.picture,
        scene.eye_plane,
        scene.max_events,
    )
