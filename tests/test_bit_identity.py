"""The default render is the same, sample for sample, across refactors (issue 10).

``tests/reference/default_render_seed1.npz`` holds ``eyelume.render(load_scene("paper2005"),
RenderOptions(seed=1))`` as rendered by the commit that made the camera samples' stop aim take
Broyden-updated steps and reuse its own trace up to the stop (a deliberate change of the samples
at rounding level: each aim converges to another point within its 1e-4 mm tolerance; 5507 of 5655
pixels moved, median 8e-8, at most 1.6e-6 and 0.2 of the pixel's own standard error; the eye
plane unchanged); before it, by the commit that gave the specular connections through
the cornea and the elements an analytic Jacobian instead of forward differences (a deliberate
change of the samples at rounding level: 763 of 5655 pixels moved, median 2e-7, at most 0.17
of the pixel's own standard error; the eye plane unchanged); before it, by the commit that made
each LED's light paths aim one in
eight of their draws at its glint's specular point (``CameraTables.glint_aim``; a deliberate
change of the samples, not of what they estimate: 934 of 5655 pixels moved — those the light
paths reach — median 0.14 %, the image's sum −0.03 %, the variance's −62 %, the glints' noise;
the eye plane unchanged); before it, by the commit that made the first vertex's continuation
skip its free cone (``geometry.free_cone``: the directions about the normal that meet nothing
able to send light back; a deliberate change of the samples, not of what they estimate: the
estimator agreement tests hold; 4810 of 5655 pixels moved, median 0.4 %, the median skin pixel's
error 0.89 % → 0.80 %); before it, by the commit that made a camera path's later vertex on the
iris connect through the cornea to one LED drawn uniformly (× the LED count) instead of to every
LED (a deliberate change of the samples, not of what they estimate: the estimator agreement
tests hold; 593 of 5655 pixels moved, median 8e-5); before it, by the commit that made the fast
camera paths continue from their first vertex in stratified directions
(``run.continuation_grid``) and draw the LED of a later vertex's NEE by its unshadowed
irradiance (likewise deliberate); before that, by the commit that closed the eye with the iris
root (issue 12), and before that at commit 3b58b61. On that machine the arrays are bit-identical
(their SHA-256 are in ``benchmarks/results/bit_identity.json``, checked exactly by ``python
benchmarks/bit_identity.py``); here the comparison allows 1e-9
relative so a CPU whose libm rounds a last bit differently still passes, while any change of a
sample, a stream or a weight (which moves pixels by 1e-3 or more) fails.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import eyelume
from eyelume.compile import compile_scene

REF = Path(__file__).parent / "reference" / "default_render_seed1.npz"


def assert_variance_matches(var, ref_var, ref_image, err_msg: str = "") -> None:
    """The per-pixel variance of the mean against its reference. It is a difference of two
    second moments of the samples, each of the size of ``image²`` (fast_run: ``(Σx² − n·x̄²) /
    (n(n − 1))``), so a last-bit difference of a sum (a CPU whose SIMD width or libm changes the
    order or the rounding) moves it by some ulps of ``image²``, not of ``var``: seen in CI, 16 of
    6400 pixels apart by 2e-16 · image² (4e-7 of their variance), on a machine other than the
    one that recorded the reference. The tolerance is 1e-9 · var + 1e-14 · image² (some 45
    ulps of image²): the CI differences are 2 % of it, while in these references 99 % of the
    pixels have var ≥ 1e-8 · image², where a change of the variance by 1e-6 of itself still fails
    (a moved sample moves it by far more; the few nearly noiseless pixels, var down to 6e-14 ·
    image², are held to a fraction of their own variance)."""
    var, ref_var, ref_image = (np.asarray(a, dtype=float) for a in (var, ref_var, ref_image))
    assert var.shape == ref_var.shape, (err_msg, var.shape, ref_var.shape)
    finite = np.isfinite(ref_var)
    np.testing.assert_array_equal(np.isfinite(var), finite, err_msg=err_msg)
    tol = 1e-9 * np.abs(ref_var) + 1e-14 * ref_image**2
    bad = finite & ~(np.abs(var - ref_var) <= tol)
    worst = float(np.max(np.abs(var - ref_var)[bad] / tol[bad])) if bad.any() else 0.0
    assert not bad.any(), (
        f"{err_msg}: {int(bad.sum())} of {bad.size} pixels off by more than"
        f" 1e-9 var + 1e-14 image², the worst {worst:.3g} × that"
    )


def test_default_render_matches_recorded_reference():
    ref = np.load(REF)
    r = eyelume.render(eyelume.load_scene("paper2005"), eyelume.RenderOptions(seed=1))
    np.testing.assert_allclose(r.eye_image, ref["eye_image"], rtol=1e-9, atol=0)
    assert_variance_matches(r.eye_image_variance, ref["eye_image_variance"], ref["eye_image"])
    np.testing.assert_allclose(r.eye_plane, ref["eye_plane"], rtol=1e-9, atol=0)


def test_chunks_of_work_change_nothing(monkeypatch):
    """Ctrl-C is looked at between chunks of camera samples and light paths (and bands of rows
    of the region map); the chunking must not move a sample: the reference again with many
    small chunks, and the same region map in bands as in one piece."""
    from eyelume.estimators import fast_run

    monkeypatch.setattr(fast_run, "CHUNK_SAMPLES", 1000)
    monkeypatch.setattr(fast_run, "CHUNK_PATHS", 3001)
    ref = np.load(REF)
    r = eyelume.render(eyelume.load_scene("paper2005"), eyelume.RenderOptions(seed=1))
    np.testing.assert_allclose(r.eye_image, ref["eye_image"], rtol=1e-9, atol=0)
    assert_variance_matches(r.eye_image_variance, ref["eye_image_variance"], ref["eye_image"])
    r_cs = compile_scene(r.scene)
    banded = fast_run.primary_surface_map(r_cs)
    monkeypatch.setattr(fast_run, "CHUNK_SAMPLES", 1 << 20)  # the whole 87 × 65 in one band
    whole = fast_run.primary_surface_map(r_cs)
    for a, b in zip(banded, whole, strict=True):
        np.testing.assert_array_equal(a, b)
