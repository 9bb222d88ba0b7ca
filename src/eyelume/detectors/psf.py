"""The camera's point-spread function on the sensor: diffraction by its circular pupil.

The tracer images the scene geometrically (aberrations and defocus included, diffraction not).
The image the sensor records is, in incoherent imaging, that geometric irradiance convolved with
the optics' diffraction point-spread function (Goodman, *Introduction to Fourier Optics*, 3rd
ed., §6.3; Born & Wolf, *Principles of Optics*, §8.5.2). For an aberration-free circular pupil
the PSF is the Airy pattern; normalised to unit power (1/mm²),

    PSF(r) = π / (4 λ² N_w²) · [2 J₁(v) / v]²,    v = π r / (λ N_w),

with λ the wavelength (in the image-side medium, air here) and N_w the image-side working
F-number (:class:`eyelume.compile.FirstOrder`: N (1 + |m|) for an ideal lens). Its encircled
energy has the closed form (Born & Wolf §8.5.2, eq. 25)

    EE(r) = 1 − J₀²(v) − J₁²(v),

the first dark ring at r = 1.22 λ N_w. Its second moment diverges (the rings fall as r⁻³), so
the pattern is truncated at the radius R where EE(R) = :data:`ENCIRCLED_ENERGY` (99 %) and
renormalised: the 1 % beyond R is redistributed proportionally inside it, so the kernel conserves
the picture's power exactly (:attr:`PixelPsf.raw_sum` is EE(R) before that, reported).

**Over pixels.** The picture holds each pixel's mean geometric irradiance Eᵢ, not where inside
the pixel the light fell. Taking it uniform over the pixel, the mean of the convolved irradiance
over pixel j is exactly

    E′ⱼ = Σᵢ K(j − i) Eᵢ,   K(d) = ∫ PSF(u) Λ(u − d p) d²u,

with Λ the pixel aperture's normalised autocorrelation, Λ(x, y) = tri(x / p_x) tri(y / p_y)
(tri(t) = max(0, 1 − |t|)): the PSF integrated over the receiving pixel's area and averaged over
the sending one's. Σ_d Λ(u − d p) = 1 for every u, so Σ_d K(d) = ∫ PSF: the pixels lose no
power. K is computed by the midpoint rule on a grid of cells :data:`CELLS_PER_LAMBDA_N` per
λ N_w, aligned to the pixel lattice (Λ is linear within each cell).

**Approximations (stated).** Shift invariance: one kernel for the whole field, the on-axis
Airy pattern (off axis the pupil is seen foreshortened and N_w grows by up to 1/cos θ′, ~6 %
radially at 20° in the image); diffraction applied after the geometric blur (a convolution of
the two, first order in each: exact when either dominates); monochromatic at the scene's
wavelength. **Edges:** the light from beyond the picture's border is not traced; a pixel
within the kernel's reach of the edge takes the kernel's weights over the pixels that exist,
renormalised, E′ⱼ = Σᵢ K(j − i) Eᵢ / Σᵢ K(j − i) (normalised convolution): a uniform field
stays uniform to its edge, the picture's power is conserved away from the edges (exactly, when
it is dark within twice the kernel's reach of them), and each traced pixel enters each convolved one
once, so the variance below is exact. (Mirroring the picture at its edge would conserve the
power there too, but uses an edge pixel twice in one sum, correlating its noise with itself.)

**Glints: light at its own position.** A glint is the image of a point LED in the cornea (or
in an element): geometrically a spot far smaller than a 3 µm pixel, so "uniform over the
pixel" throws away where in the pixel it fell, and the convolved spot would be symmetric about
the pixel's centre whatever the truth (up to 0.38 px off on vr-offaxis). The light that met no
Lambertian face (the estimators keep it apart, with its first moments inside each pixel) is
therefore taken as a point at its centroid s = (s_x, s_y) (pixels, from the pixel's centre) and
spread by the PSF integrated over the receiving pixels only,

    P(d; s) = ∫ PSF(u) B(u + s p − d p) d²u,   B the pixel's aperture (a box),

whose mean over s uniform in the pixel is K(d) (B ⊗ B = Λ), so a glint spread over many pixels
gets the same picture either way. P is tabulated at s = −½ + a / :data:`POINT_OFFSETS` in each
axis (the same midpoint cells, each cell's exact overlap with the shifted pixel) and
interpolated bilinearly in s (:func:`point_kernels`, :func:`spread_points`); each P(·; s) is
renormalised to sum 1, so the glint keeps its power. Approximations (stated): all of a pixel's
glint light sits at its centroid (its spread inside the pixel, a defocused glint's, is lost);
the variance keeps K² (:func:`convolve_variance`: the glint light's own second moments are not
kept apart).

**Variance.** The operator is linear; for independent pixel estimates Var(E′ⱼ) = Σᵢ K(j − i)²
Var(Eᵢ) (:func:`convolve_variance`). The fast estimator's pixels are independent up to its
light paths' multinomial split between pixels (a negative covariance of order 1 / paths,
neglected); the forward counts are multinomial likewise. The convolved pixels are then
correlated with their neighbours: a sum over a region has the variance Σᵢ wᵢ² Var(Eᵢ) with
w = K ⊗ mask, not the sum of the convolved variances (:func:`region_mean_variance`).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy import optimize, signal, special

from eyelume.compile import CompiledScene
from eyelume.kernels.bins import PlaneGrid

__all__ = [
    "CELLS_PER_LAMBDA_N",
    "ENCIRCLED_ENERGY",
    "PixelPsf",
    "airy_encircled_energy",
    "airy_psf",
    "airy_radius_for_energy",
    "camera_psf",
    "convolve_irradiance",
    "POINT_OFFSETS",
    "convolve_variance",
    "convolve_with_points",
    "diffraction_kernel",
    "point_kernels",
    "spread_points",
    "region_mean_variance",
]

#: The Airy pattern is truncated at the radius enclosing this fraction of its power.
ENCIRCLED_ENERGY = 0.99
#: Midpoint-rule cells per λ N_w (the Airy core's scale: first dark ring at 1.22 λ N_w).
CELLS_PER_LAMBDA_N = 24
#: Sub-pixel steps per pixel of the glint (point) kernels' table, :func:`point_kernels`.
POINT_OFFSETS = 16


def airy_psf(r_mm, wavelength_mm: float, working_f_number: float):
    """The Airy pattern normalised to unit power: π / (4 λ² N²) [2 J₁(v)/v]², v = π r / (λ N).

    ``r_mm`` any shape (mm from the centre), λ in mm; returns 1/mm², same shape.
    """
    ln = wavelength_mm * working_f_number
    v = np.pi * np.asarray(r_mm, dtype=np.float64) / ln
    safe = np.where(v == 0.0, 1.0, v)
    amp = np.where(v == 0.0, 1.0, 2.0 * special.j1(safe) / safe)
    return np.pi / (4.0 * ln * ln) * amp * amp


def airy_encircled_energy(r_mm, wavelength_mm: float, working_f_number: float):
    """Power fraction of the Airy pattern within radius r: 1 − J₀²(v) − J₁²(v) (Born & Wolf
    §8.5.2), v = π r / (λ N); ``r_mm`` any shape."""
    v = np.pi * np.asarray(r_mm, dtype=np.float64) / (wavelength_mm * working_f_number)
    return 1.0 - special.j0(v) ** 2 - special.j1(v) ** 2


def airy_radius_for_energy(fraction: float, wavelength_mm: float, working_f_number: float) -> float:
    """The smallest radius (mm) whose encircled energy reaches ``fraction`` (0 < fraction < 1).

    EE is not monotonic between rings' maxima only in flat steps: it never decreases, so the
    first crossing is found by stepping out in quarter-ring steps and refining by Brent."""
    ln = wavelength_mm * working_f_number
    step = 0.25 * ln  # the rings are λN apart
    r = step
    while airy_encircled_energy(r, wavelength_mm, working_f_number) < fraction:
        r += step
    return float(
        optimize.brentq(
            lambda x: airy_encircled_energy(x, wavelength_mm, working_f_number) - fraction,
            r - step,
            r,
            xtol=1e-12 * ln,
        )
    )


@dataclass(frozen=True)
class PixelPsf:
    """A point-spread function on the picture's pixel lattice (see the module docstring).

    Attributes
    ----------
    kind : str
        ``"diffraction"``.
    kernel : (2 ky + 1, 2 kx + 1) float64
        K(d) renormalised to sum 1; row index dy + ky (picture rows), column dx + kx.
    wavelength_nm, working_f_number : float
        λ and N_w of the Airy pattern.
    pitch_mm : (float, float)
        The picture's pixel pitch (x, y) on the sensor (mm).
    airy_radius_mm : float
        The first dark ring, 1.22 λ N_w (mm).
    truncation_radius_mm : float
        R, where EE(R) = :data:`ENCIRCLED_ENERGY`.
    raw_sum : float
        Σ K before renormalisation: the midpoint rule's EE(R) (the power kept, ~0.99).
    """

    kind: str
    kernel: np.ndarray
    wavelength_nm: float
    working_f_number: float
    pitch_mm: tuple[float, float]
    airy_radius_mm: float
    truncation_radius_mm: float
    raw_sum: float

    def summary(self) -> dict:
        """JSON-ready facts of the kernel (``summary.json``)."""
        ky, kx = self.kernel.shape[0] // 2, self.kernel.shape[1] // 2
        return {
            "kind": self.kind,
            "wavelength_nm": self.wavelength_nm,
            "working_f_number": self.working_f_number,
            "airy_radius_um": self.airy_radius_mm * 1e3,
            "airy_radius_pixels": self.airy_radius_mm / self.pitch_mm[0],
            "truncation_radius_um": self.truncation_radius_mm * 1e3,
            "encircled_energy_kept": self.raw_sum,
            "kernel_shape": list(self.kernel.shape),
            "centre_pixel_share": float(self.kernel[ky, kx]),
            "note": (
                "Airy pattern truncated where its encircled energy reaches "
                f"{ENCIRCLED_ENERGY:.0%} and renormalised; integrated over the pixels; one kernel "
                "for the whole field (on-axis, shift-invariant); at the picture's edges the "
                "kernel's weights over existing pixels, renormalised; the light that met no "
                "Lambertian face (glints) spread from its centroid inside its pixel"
            ),
        }


def _tri_weights(centres_mm: np.ndarray, pitch_mm: float, k: int) -> np.ndarray:
    """(2k + 1, n): tri((u − d p) / p) for d = −k … k at the cells' centres u."""
    d = np.arange(-k, k + 1, dtype=np.float64)[:, None] * pitch_mm
    return np.maximum(0.0, 1.0 - np.abs(centres_mm[None, :] - d) / pitch_mm)


@lru_cache(maxsize=16)
def diffraction_kernel(
    wavelength_nm: float,
    working_f_number: float,
    pitch_x_mm: float,
    pitch_y_mm: float,
    encircled_energy: float = ENCIRCLED_ENERGY,
    cells_per_lambda_n: int = CELLS_PER_LAMBDA_N,
) -> PixelPsf:
    """The Airy pattern of λ = ``wavelength_nm`` and N_w = ``working_f_number`` on a pixel
    lattice of pitch (``pitch_x_mm``, ``pitch_y_mm``): K(d) = ∫_{|u| ≤ R} PSF(u) Λ(u − d p) d²u
    over the disc where EE(R) = ``encircled_energy``, by the midpoint rule on square cells of
    side h ≤ λ N_w / ``cells_per_lambda_n`` aligned so that every pixel centre is a cell corner,
    then divided by its sum (module docstring). Cached by its arguments (a tracking run asks
    for the same kernel every frame); the kernel array is read-only.

    Raises
    ------
    ValueError
        A non-positive or non-finite wavelength, F-number or pitch, or a fraction outside (0, 1).
    """
    for name, val in (
        ("wavelength_nm", wavelength_nm),
        ("working_f_number", working_f_number),
        ("pitch_x_mm", pitch_x_mm),
        ("pitch_y_mm", pitch_y_mm),
    ):
        if not (math.isfinite(val) and val > 0):
            raise ValueError(f"{name} = {val!r}: must be a positive number")
    if not 0.0 < encircled_energy < 1.0:
        raise ValueError(f"encircled_energy = {encircled_energy!r}: must lie in (0, 1)")
    lam = wavelength_nm * 1e-6
    ln = lam * working_f_number
    (cx, hx), (cy, hy), cells, radius = _airy_cells(
        lam, working_f_number, pitch_x_mm, pitch_y_mm, encircled_energy, cells_per_lambda_n
    )
    wx = _tri_weights(cx, pitch_x_mm, math.ceil(radius / pitch_x_mm))
    wy = _tri_weights(cy, pitch_y_mm, math.ceil(radius / pitch_y_mm))
    kernel = wy @ cells @ wx.T
    raw = float(kernel.sum())
    kernel = kernel / raw
    kernel.setflags(write=False)
    return PixelPsf(
        kind="diffraction",
        kernel=kernel,
        wavelength_nm=float(wavelength_nm),
        working_f_number=float(working_f_number),
        pitch_mm=(float(pitch_x_mm), float(pitch_y_mm)),
        airy_radius_mm=1.2196698912665045 * ln,  # first zero of J₁ / π
        truncation_radius_mm=radius,
        raw_sum=raw,
    )


@lru_cache(maxsize=4)
def _airy_cells(lam_mm, working_f_number, pitch_x_mm, pitch_y_mm, encircled_energy, per_ln):
    """The Airy pattern's power in midpoint cells over the disc where EE(R) = ``encircled_energy``:
    ((x centres, hx), (y centres, hy), cells (ny, nx) — PSF × cell area, 0 beyond R —, R), the
    cells of side h ≤ λ N_w / ``per_ln`` aligned so that every pixel centre is a cell corner.
    Cached (the pixel kernel and the point kernels share them); read-only."""
    ln = lam_mm * working_f_number
    radius = airy_radius_for_energy(encircled_energy, lam_mm, working_f_number)
    axes = []
    for pitch in (pitch_x_mm, pitch_y_mm):
        per_pixel = max(1, math.ceil(pitch / (ln / per_ln)))
        h = pitch / per_pixel
        m = math.ceil(radius / h)
        axes.append(((np.arange(-m, m) + 0.5) * h, h))
    (cx, hx), (cy, hy) = axes
    r = np.hypot(cy[:, None], cx[None, :])
    cells = np.where(r <= radius, airy_psf(r, lam_mm, working_f_number), 0.0) * (hx * hy)
    for a in (cx, cy, cells):
        a.setflags(write=False)
    return (cx, hx), (cy, hy), cells, radius


def _pixel_sums(cells: np.ndarray, m: int, h: float, pitch: float, k: int, steps) -> np.ndarray:
    """Σ over cells of their power inside each receiving pixel along axis 0, for a point moved
    by s pixels: out[a, d + k] = Σ_u cells[u] · |[u − h/2, u + h/2] + s_a p ∩ [d p ± p/2]| / h
    for d = −k … k, each s_a of ``steps``; shape (len(steps), 2k + 1, *cells.shape[1:]). By the
    cumulative sum of the cells, interpolated linearly inside a cell (exact: each cell's power
    is uniform over it in the midpoint rule); the cells span [−m h, m h]."""
    cum = np.concatenate([np.zeros((1, *cells.shape[1:])), np.cumsum(cells, axis=0)])
    d = np.arange(-k, k + 1, dtype=np.float64)
    out = []
    for s in steps:
        ends = []
        for edge in (d - s - 0.5, d - s + 0.5):
            t = np.clip(edge * pitch / h + m, 0.0, 2 * m)
            i = np.minimum(t.astype(np.int64), 2 * m - 1)
            frac = (t - i).reshape(-1, *([1] * (cells.ndim - 1)))
            ends.append(cum[i] + frac * (cum[i + 1] - cum[i]))
        out.append(ends[1] - ends[0])
    return np.stack(out)


@lru_cache(maxsize=16)
def point_kernels(
    wavelength_nm: float,
    working_f_number: float,
    pitch_x_mm: float,
    pitch_y_mm: float,
    encircled_energy: float = ENCIRCLED_ENERGY,
    cells_per_lambda_n: int = CELLS_PER_LAMBDA_N,
    offsets: int = POINT_OFFSETS,
) -> np.ndarray:
    """The table of a point's kernels P(d; s) (module docstring, "Glints"): shape
    (M + 1, M + 1, 2k + 3, 2k + 3), M = ``offsets``, item [b, a] the kernel of a point at
    s = (−½ + a / M, −½ + b / M) pixels from its pixel's centre (x: columns, y: rows), its
    row index dy + k + 1 and column dx + k + 1 (k = ⌈R / p⌉, as :func:`diffraction_kernel`;
    one pixel more for the shift). Each kernel sums to 1. The Airy cells are
    :func:`diffraction_kernel`'s; each one's exact overlap with the shifted receiving pixel
    weighs it (by cumulative sums, :func:`_pixel_sums`). Cached; read-only.

    Raises
    ------
    ValueError
        As :func:`diffraction_kernel`; ``offsets`` < 1.
    """
    diffraction_kernel(wavelength_nm, working_f_number, pitch_x_mm, pitch_y_mm, encircled_energy)
    if offsets < 1:
        raise ValueError(f"offsets = {offsets!r}: must be ≥ 1")
    lam = wavelength_nm * 1e-6
    (cx, hx), (cy, hy), cells, radius = _airy_cells(
        lam, working_f_number, pitch_x_mm, pitch_y_mm, encircled_energy, cells_per_lambda_n
    )
    kx, ky = math.ceil(radius / pitch_x_mm) + 1, math.ceil(radius / pitch_y_mm) + 1
    steps = -0.5 + np.arange(offsets + 1) / offsets
    # along x for every x offset: (M + 1, 2kx + 1, ny cells); then along y for every y offset
    by_x = _pixel_sums(cells.T, cx.size // 2, hx, pitch_x_mm, kx, steps)
    table = _pixel_sums(by_x.transpose(2, 0, 1), cy.size // 2, hy, pitch_y_mm, ky, steps)
    table = table.transpose(0, 2, 1, 3)  # [b, a, dy, dx]
    table = np.ascontiguousarray(table / table.sum(axis=(2, 3), keepdims=True))
    table.setflags(write=False)
    return table


#: Points spread per pass of :func:`spread_points` (bounds its memory: n × kernel size).
_SPREAD_BATCH = 1024


def spread_points(values: np.ndarray, offsets: np.ndarray, table: np.ndarray) -> np.ndarray:
    """Σᵢ P(j − i; sᵢ) vᵢ: each pixel's ``values`` (rows, cols; W/mm²) taken as a point at its
    centroid sᵢ = ``offsets``[:, i] ((2, rows, cols): columns, rows; pixels from the pixel's
    centre, within ±½) and spread by the point kernel there, bilinear between the ``table``'s
    (:func:`point_kernels`) nearest offsets. Zero outside the picture (what falls beyond its
    edge is lost, as in :func:`convolve_irradiance` before its normalisation); (rows, cols)."""
    rows, cols = values.shape
    out_shape = (rows + table.shape[2] - 1, cols + table.shape[3] - 1)
    ky, kx = table.shape[2] // 2, table.shape[3] // 2
    m = table.shape[0] - 1
    flat = table.reshape(m + 1, m + 1, -1)
    idx = np.flatnonzero(values)
    out = np.zeros(out_shape[0] * out_shape[1])
    dy, dx = np.divmod(np.arange(flat.shape[2]), table.shape[3])
    window = dy * out_shape[1] + dx  # the kernel's pixels in the padded picture, from its corner
    for a0 in range(0, idx.size, _SPREAD_BATCH):
        i = idx[a0 : a0 + _SPREAD_BATCH]
        r, c = np.divmod(i, cols)
        v = values.reshape(-1)[i]
        fx = (np.clip(offsets[0].reshape(-1)[i], -0.5, 0.5) + 0.5) * m
        fy = (np.clip(offsets[1].reshape(-1)[i], -0.5, 0.5) + 0.5) * m
        ax, ay = np.minimum(fx.astype(np.int64), m - 1), np.minimum(fy.astype(np.int64), m - 1)
        tx, ty = (fx - ax)[:, None], (fy - ay)[:, None]
        kern = (1 - ty) * ((1 - tx) * flat[ay, ax] + tx * flat[ay, ax + 1]) + ty * (
            (1 - tx) * flat[ay + 1, ax] + tx * flat[ay + 1, ax + 1]
        )
        corner = r * out_shape[1] + c  # the kernel's corner sits ky, kx before the pixel
        out += np.bincount(
            (corner[:, None] + window[None, :]).reshape(-1),
            weights=(kern * v[:, None]).reshape(-1),
            minlength=out.size,
        )
    return out.reshape(out_shape)[ky : ky + rows, kx : kx + cols]


def convolve_with_points(
    irradiance: np.ndarray, points: np.ndarray, offsets: np.ndarray, psf: PixelPsf | None
) -> np.ndarray:
    """The delivered picture of a traced one whose part ``points`` (rows, cols; W/mm², ≤
    ``irradiance``) is light at its pixels' centroids ``offsets`` (2, rows, cols; pixels): the
    rest convolved with K (:func:`convolve_irradiance`), ``points`` spread by P(·; s)
    (:func:`spread_points`), the sum normalised at the edges alike (module docstring). None
    ``psf``: ``irradiance`` unchanged. Raises ValueError on a non-finite pixel."""
    if psf is None:
        return irradiance
    if not np.all(np.isfinite(irradiance)):
        raise ValueError("the PSF needs every pixel: the picture has missing (NaN) pixels")
    e = np.asarray(irradiance, dtype=np.float64)
    g = np.minimum(np.asarray(points, dtype=np.float64), e)
    table = point_kernels(psf.wavelength_nm, psf.working_f_number, *psf.pitch_mm)
    rest = _zero_padded(e - g, psf.kernel)  # all zeros when no light is left
    return (rest + spread_points(g, offsets, table)) / _weights(e.shape, psf.kernel)


def camera_psf(cs: CompiledScene) -> PixelPsf | None:
    """The PSF of a compiled scene's camera (``camera.psf_used``; None for ``"none"``): the
    Airy pattern at the scene's wavelength and the camera's working F-number
    (:attr:`eyelume.compile.FirstOrder.working_f_number`) on the picture's pixels."""
    if cs.scene.camera.psf_used == "none":
        return None
    pic: PlaneGrid = cs.picture
    return diffraction_kernel(
        cs.scene.wavelength_nm,
        cs.first_order.working_f_number,
        pic.width_mm / pic.cols,
        pic.height_mm / pic.rows,
    )


def _zero_padded(a: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """a ⊗ kernel (odd, centred), zero outside ``a``, same shape; by FFT. Its round-off (~1e-16
    of the largest value, of either sign) is clipped at zero (every input and kernel here is
    ≥ 0) and removed where no non-zero input is within the kernel's reach, so a dark pixel
    away from all light stays exactly 0."""
    if kernel.shape == (1, 1) or not a.any():
        return a * kernel[0, 0] if kernel.shape == (1, 1) else np.zeros(a.shape)
    crop = _reach(a, kernel)
    if crop is not None:  # a compact spot (a glint's picture): convolve the part that matters
        out = np.zeros(a.shape)
        out[crop] = _zero_padded(a[crop], kernel)
        return out
    out = np.maximum(signal.fftconvolve(a, kernel, mode="same"), 0.0)
    # how many non-zero inputs each output sees through the kernel's footprint (integers: the
    # FFT's error is far below ½)
    seen = signal.fftconvolve((a != 0).astype(np.float64), (kernel > 0).astype(np.float64), "same")
    out[seen < 0.5] = 0.0
    return out


def _reach(a: np.ndarray, kernel: np.ndarray) -> tuple[slice, slice] | None:
    """The rectangle of ``a`` holding its non-zero pixels grown by the kernel's half-size, when
    it is under half the picture (else None): every output pixel outside it is 0, every one
    inside sees only inputs inside it, so the rectangle's own zero-padded convolution is the
    picture's there."""
    rows, cols = np.flatnonzero(a.any(axis=1)), np.flatnonzero(a.any(axis=0))
    if rows.size == 0:
        return None
    ky, kx = kernel.shape[0] // 2, kernel.shape[1] // 2
    r0, r1 = max(rows[0] - ky, 0), min(rows[-1] + ky + 1, a.shape[0])
    c0, c1 = max(cols[0] - kx, 0), min(cols[-1] + kx + 1, a.shape[1])
    if 2 * (r1 - r0) * (c1 - c0) >= a.size:
        return None
    return np.s_[r0:r1, c0:c1]


def _weights(shape: tuple[int, int], kernel: np.ndarray) -> np.ndarray:
    """W_j = Σ_{i in the picture} K(j − i): 1 inside, less within the kernel's reach of an edge
    (read-only; one computation per picture shape and kernel, :func:`_cached_weights`)."""
    k = np.ascontiguousarray(kernel, dtype=np.float64)
    return _cached_weights(tuple(shape), k.shape, k.tobytes())


@functools.lru_cache(maxsize=8)
def _cached_weights(shape: tuple[int, int], kshape: tuple[int, int], kbytes: bytes) -> np.ndarray:
    kernel = np.frombuffer(kbytes, dtype=np.float64).reshape(kshape)
    w = _zero_padded(np.ones(shape), kernel)
    w.flags.writeable = False
    return w


def convolve_irradiance(irradiance: np.ndarray, psf: PixelPsf | None) -> np.ndarray:
    """The picture's irradiance (rows, cols; W/mm²) convolved with ``psf`` (None: returned
    unchanged, the same array). Raises ValueError on a non-finite pixel (a render whose first
    round was cut: its missing pixels have no neighbours' light to spread)."""
    if psf is None:
        return irradiance
    if not np.all(np.isfinite(irradiance)):
        raise ValueError("the PSF needs every pixel: the picture has missing (NaN) pixels")
    e = np.asarray(irradiance, dtype=np.float64)
    return _zero_padded(e, psf.kernel) / _weights(e.shape, psf.kernel)


def convolve_variance(variance: np.ndarray, psf: PixelPsf | None) -> np.ndarray:
    """Each convolved pixel's variance from independent pixels' ``variance``: K² ⊗ Var (module
    docstring). An unknown variance (+inf anywhere) stays unknown: returned unchanged."""
    if psf is None or not np.all(np.isfinite(variance)):
        return variance
    v = np.asarray(variance, dtype=np.float64)
    return _zero_padded(v, psf.kernel**2) / _weights(v.shape, psf.kernel) ** 2


def region_mean_variance(mask: np.ndarray, variance: np.ndarray, psf: PixelPsf | None) -> float:
    """Variance of the mean of the convolved picture over ``mask`` (rows, cols bool), from the
    independent pixels' ``variance`` before the convolution: Σᵢ wᵢ² Var(Eᵢ) with wᵢ = Σ_{j in
    mask} K(j − i) / (n W_j) = (K ⊗ (mask / W))ᵢ / n (K is symmetric). Without a PSF, Σ Var / n²
    over the mask."""
    n = int(np.count_nonzero(mask))
    if n == 0:
        return 0.0
    if psf is None:
        return float(variance[mask].sum()) / (n * n)
    weights = _weights(mask.shape, psf.kernel)
    w = _zero_padded(mask / weights, psf.kernel) / n
    return float(np.sum(w * w * variance))
