"""The fast estimator's parts against closed forms and independent estimators, its noise
estimates against the scatter of independent runs, and its determinism."""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest
from numba import njit
from scipy import stats

import eyelume
from eyelume.compile import compile_scene
from eyelume.estimators import fast as F
from eyelume.estimators.camera import Mat2, aim_at_stop, aim_chief, into_scene
from eyelume.kernels import geometry as G
from eyelume.kernels.rng import stream_start
from eyelume.kernels.sampling import cos_power_tables
from eyelume.kernels.tables import A_P, A_R, A_Z, N_AIM, Facet, LedTable, SurfaceTable
from eyelume.scene.sources import cos_power_exponent

SMALL = {"sensor.cols": 29, "sensor.rows": 22}  # 1.6 mm pixels: quick renders


@pytest.fixture(scope="module")
def cam(paper_compiled):
    return paper_compiled.camera


def aimed_values(cs, cam, xs, ys, n, seed):
    """A_stop cos²θ / (d² |det J|) for n uniform stop points seen from sensor point (xs, ys):
    each an unbiased estimate of ∫ cos θ dω over the directions that pass the lens."""
    rng = np.random.default_rng(seed)
    found, qcx, qcy, (a11, a12, a21, a22) = aim_chief(cam, xs, ys)
    assert found
    det_c = a11 * a22 - a12 * a21
    r = cam.stop_radius * np.sqrt(rng.random(n))
    phi = 2 * np.pi * rng.random(n)
    out = np.empty(n)
    for i, (tx, ty) in enumerate(zip(r * np.cos(phi), r * np.sin(phi), strict=True)):
        ok, qx, qy, det = aim_at_stop(
            cam,
            xs,
            ys,
            tx,
            ty,
            qcx + (a22 * tx - a12 * ty) / det_c,
            qcy + (-a21 * tx + a11 * ty) / det_c,
            Mat2(a11, a12, a21, a22),
        )
        assert ok
        passed, *_, g = into_scene(cam, xs, ys, qx, qy)
        out[i] = math.pi * cam.stop_radius**2 * g / det if passed else 0.0
    return out


def test_stop_aiming_gives_the_image_space_cone_on_axis(paper_compiled, cam):
    """On axis the rays through the stop fill a circular cone of half-angle θ′ (the real rim
    ray's angle at the sensor): ∫ cos θ dω = π sin²θ′."""
    cs = paper_compiled
    vals = aimed_values(cs, cam, 0.0, 0.0, 3000, 1)
    rim = aimed_values(cs, cam, 0.0, 0.0, 1, 2)  # just to exercise the path at one point
    assert rim.shape == (1,)
    # the rim ray: aim at the stop's edge, then its direction at the sensor gives θ′
    found, qcx, qcy, (a11, a12, a21, a22) = aim_chief(cam, 0.0, 0.0)
    det_c = a11 * a22 - a12 * a21
    t = cam.stop_radius * (1 - 1e-9)
    ok, qx, qy, _ = aim_at_stop(
        cam,
        0.0,
        0.0,
        t,
        0.0,
        qcx + a22 * t / det_c,
        qcy - a21 * t / det_c,
        Mat2(a11, a12, a21, a22),
    )
    assert ok
    sin2 = (qx**2 + qy**2) / (qx**2 + qy**2 + (cs.image_z - cam.rear_z) ** 2)
    expected = math.pi * sin2
    sem = vals.std(ddof=1) / math.sqrt(vals.size)
    assert abs(vals.mean() - expected) < 4 * sem + 1e-4 * expected


def test_stop_aiming_agrees_with_hit_or_miss_off_axis(paper_compiled, cam):
    """At a field corner, the aimed estimate of ∫ cos θ dω over the passing directions equals
    the hit-or-miss one (uniform points of a disk twice the paraxial pupil's size, kept when
    the lens passes them) within 4σ."""
    cs = paper_compiled
    xs, ys = 0.45 * cs.picture.width_mm, 0.45 * cs.picture.height_mm
    aimed = aimed_values(cs, cam, xs, ys, 2000, 3)
    s = (cs.image_z - cam.rear_z) / (cs.image_z - cam.exit_pupil_z)
    cx, cy = xs * (1 - s), ys * (1 - s)
    rad = 2.0 * abs(cam.exit_pupil_magnification) * cam.stop_radius * s
    rng = np.random.default_rng(4)
    n = 40_000
    r = rad * np.sqrt(rng.random(n))
    phi = 2 * np.pi * rng.random(n)
    hits = np.empty(n)
    for i in range(n):
        passed, *_, g = into_scene(
            cam, xs, ys, cx + r[i] * math.cos(phi[i]), cy + r[i] * math.sin(phi[i])
        )
        hits[i] = math.pi * rad**2 * g if passed else 0.0
    assert 0.1 < (hits > 0).mean() < 0.5  # the wide disk holds the whole passing pupil
    diff = aimed.mean() - hits.mean()
    sigma = math.hypot(aimed.std(ddof=1) / math.sqrt(aimed.size), hits.std(ddof=1) / math.sqrt(n))
    assert abs(diff) < 4 * sigma


def test_direct_irradiance_is_inverse_square_with_both_cosines():
    """E = I₀ cosᵐα cos θ / d² from one LED in empty space."""
    m = cos_power_exponent(22.5)
    ag, cdf, _ = cos_power_tables(m)
    ig = np.cos(ag) ** m
    axis = np.array([0.3, -0.2, -1.0])
    axis /= np.linalg.norm(axis)
    i0, one = np.array([0.015]), np.ones(1)
    leds = LedTable(
        np.array([[5.0, 8.0, 60.0]]), np.array([axis]), i0, ag, cdf[None], ig[None], one, True
    )
    surfaces = SurfaceTable(np.zeros((0, G.N_FLOAT)), np.zeros((0, G.N_INT), dtype=np.int64))
    rng = np.random.default_rng(5)
    for _ in range(20):
        p = np.array([*rng.uniform(-15, 15, 2), rng.uniform(-5, 5)])
        n = np.array([*rng.uniform(-0.4, 0.4, 2), 1.0])
        n /= np.linalg.norm(n)
        v = leds.points[0] - p
        d = np.linalg.norm(v)
        cos_a = -(v / d) @ axis
        cos_t = (v / d) @ n
        expected = 0.015 * cos_a**m * cos_t / d**2 if cos_t > 0 and cos_a > 0 else 0.0
        got = F.direct_irradiance(surfaces, leds, Facet(*p, *n))
        assert got == pytest.approx(expected, rel=1e-6, abs=1e-15)


@njit
def _sampled(surfaces, leds, facet, n):
    out = np.empty(n)
    state = stream_start(7, 0)
    e_led = np.empty(leds.points.shape[0])
    for i in range(n):
        state, out[i] = F.sampled_irradiance(state, surfaces, leds, facet, e_led)
    return out


def test_sampled_irradiance_is_the_sum_over_leds_on_average():
    """One shadow ray to an LED drawn in proportion to its unshadowed irradiance, weighted by
    1/p: its mean is direct_irradiance (the sum over every LED that sees the point) when a
    sphere hides one of four LEDs, and every draw is that sum when none is hidden."""
    m = cos_power_exponent(30.0)
    ag, cdf, _ = cos_power_tables(m)
    ig = np.cos(ag) ** m
    pts = np.array([[12.0, 0.0, 30.0], [0.0, 12.0, 30.0], [-12.0, 0.0, 30.0], [0.0, -9.0, 25.0]])
    axes = -pts / np.linalg.norm(pts, axis=1)[:, None]
    i0 = np.array([0.01, 0.02, 0.005, 0.01])  # each LED its own I₀ (issue 11)
    four = np.ones((4, 1))
    leds = LedTable(pts, axes, i0, ag, cdf * four, ig * four, np.cumsum(i0) / i0.sum(), False)
    # an opaque sphere of radius 2 mm halfway to LED 0 (columns of kernels/geometry.py)
    sf = np.zeros((1, G.N_FLOAT))
    centre = np.array([6.0, 0.0, 15.0])
    sf[0, G.OX : G.OZ + 1] = centre
    sf[0, [G.R00, G.R11, G.R22]] = 1.0
    sf[0, G.RADIUS] = 2.0
    sf[0, G.RMAX2] = np.inf
    sf[0, G.ZLO], sf[0, G.ZHI] = -np.inf, np.inf
    sf[0, G.BX : G.BZ + 1] = centre
    sf[0, G.BR] = 2.0
    si = np.zeros((1, G.N_INT), dtype=np.int64)
    si[0, G.SHAPE], si[0, G.ACTION] = G.SHAPE_SPHERE, G.ACT_OPAQUE
    shadowed = SurfaceTable(sf, si)
    empty = SurfaceTable(np.zeros((0, G.N_FLOAT)), np.zeros((0, G.N_INT), dtype=np.int64))
    facet = Facet(0.0, 0.0, 0.0, 0.0, 0.0, 1.0)
    want = F.direct_irradiance(shadowed, leds, facet)
    free = F.direct_irradiance(empty, leds, facet)
    assert 0.0 < want < 0.9 * free  # LED 0 is hidden, the others are not
    draws = _sampled(shadowed, leds, facet, 200_000)
    sem = draws.std(ddof=1) / math.sqrt(draws.size)
    assert abs(draws.mean() - want) < 4 * sem
    assert np.all(_sampled(empty, leds, facet, 1000) == pytest.approx(free, rel=1e-12))


@njit
def _scatter_weights(aim, nx, ny, nz, n):
    w = np.empty(n)
    state = stream_start(99, 0)
    for i in range(n):
        state, _, _, _, f = F._scatter(state, aim, 1.0, 2.0, 0.0, nx, ny, nz)
        w[i] = f
    return w


@pytest.mark.parametrize("p_aim", [0.0, 0.5, 0.8])
def test_aimed_scatter_weights_average_one(p_aim):
    """E[(cos θ/π) / pdf_mix] = ∫ cos θ / π dω = 1 over the hemisphere, whatever the mixture:
    the mixture's density is normalised and covers every direction."""
    aim = np.zeros(N_AIM)
    aim[A_Z], aim[A_R], aim[A_P] = 150.0, 25.0, p_aim
    nrm = np.array([0.2, -0.1, 1.0])
    nrm /= np.linalg.norm(nrm)
    w = _scatter_weights(aim, *nrm, 200_000)
    n = w.size
    sem = w.std(ddof=1) / math.sqrt(n)
    assert abs(w.mean() - 1.0) < 4 * sem + 1e-12


def _small_render(seed, **kw):
    sc = eyelume.load_scene("paper2005", SMALL)
    return eyelume.render(sc, eyelume.RenderOptions(estimator="fast", seed=seed, **kw))


def test_noise_estimates_match_the_scatter_between_seeds():
    """Ten independent runs: the spread of each skin pixel and of the region means between runs
    agrees with the variances each run estimated for itself."""
    runs = [_small_render(s) for s in range(10)]
    imgs = np.stack([r.eye_image for r in runs])
    var_est = np.stack([r.eye_image_variance for r in runs]).mean(axis=0)
    k = len(runs)
    skin = runs[0].regions["skin"]
    s2 = imgs.var(axis=0, ddof=1)[skin]
    v = var_est[skin]
    ratio = s2.sum() / v.sum()
    n_eff = v.sum() ** 2 / (v**2).sum()
    tol = 4 * math.sqrt(2 / (k - 1) / n_eff + 2 / (2 * k) / n_eff)
    assert abs(ratio - 1) < tol, f"pixel scatter / estimate = {ratio:.3f} ± {tol / 4:.3f}"
    lo, hi = stats.chi2.ppf([0.0005, 0.9995], k - 1) / (k - 1)
    for region in ("skin", "iris", "sclera"):
        means = np.array([r.region_stats()[region]["mean_w_mm2"] for r in runs])
        est = np.mean([r.region_stats()[region]["mean_rel_error"] for r in runs]) * means.mean()
        q = means.var(ddof=1) / est**2
        assert lo < q < hi, f"{region}: scatter / estimate of the mean's variance = {q:.2f}"


def test_same_seed_same_image_whatever_the_thread_count(tmp_path):
    script = (
        "import sys, numpy as np, eyelume\n"
        f"sc = eyelume.load_scene('paper2005', {SMALL!r})\n"
        "opt = eyelume.RenderOptions(estimator='fast', samples_per_pixel=32, seed=8)\n"
        "r = eyelume.render(sc, opt)\n"
        "np.save(sys.argv[1], np.stack([r.eye_image, r.eye_image_variance]))\n"
    )
    out = {}
    for threads in (1, 2):
        path = tmp_path / f"t{threads}.npy"
        env = dict(os.environ, NUMBA_NUM_THREADS=str(threads))
        subprocess.run([sys.executable, "-c", script, str(path)], check=True, env=env)
        out[threads] = np.load(path)
    np.testing.assert_array_equal(out[1], out[2])


def test_rounds_do_not_change_the_result():
    """A run to a target adds rounds; the samples it drew are those of a fixed-budget run with
    the same count, so the two images are identical."""
    a = _small_render(3, rel_error=0.004)
    b = _small_render(3, samples_per_pixel=a.samples_per_pixel)
    assert a.samples_per_pixel > 32
    np.testing.assert_array_equal(a.eye_image, b.eye_image)


def test_rel_error_target_is_met():
    r = _small_render(4, rel_error=0.003)
    assert r.region_stats()["skin"]["median_pixel_rel_error"] <= 0.003


def test_fast_eye_plane_is_the_direct_irradiance(paper_compiled):
    """Away from occluders the eye plane is the LEDs' direct light: compare with the forward
    tally (all light crossing the plane toward the eye) bin by bin."""
    fwd = eyelume.render(paper_compiled, eyelume.RenderOptions(rays=4_000_000, seed=9))
    fast = eyelume.render(
        paper_compiled, eyelume.RenderOptions(estimator="fast", samples_per_pixel=32, seed=9)
    )
    keep = fwd.plane_counts >= 100
    z = (fast.eye_plane[keep] - fwd.eye_plane[keep]) / (
        fwd.eye_plane[keep] / np.sqrt(fwd.plane_counts[keep])
    )
    assert keep.sum() > 250
    lo, hi = stats.chi2.ppf([0.001, 0.999], keep.sum())
    assert lo < (z**2).sum() < hi


def test_camera_tables_reject_nothing_on_the_default_scene(paper_compiled):
    cs = compile_scene(eyelume.load_scene("paper2005", SMALL))
    t = cs.camera
    assert 0 < t.stop_radius < cs.lf[:, 3].max()
    assert t.k_stop == cs.lf.shape[0] - 1 - cs.stop_index


def test_one_led_through_the_cornea_is_the_sum_on_average():
    """A later vertex on the iris connects through the cornea to one LED drawn uniformly, × the
    LED count: that is unbiased when every LED's connection (led_through_cornea) adds up to
    the all-LED one (irradiance_through_cornea) the first vertex uses, checked at iris points of
    vr-offaxis where several LEDs reach through the cornea; the side uniform that draws the
    LED leaves the path's stream as it was and is uniform."""
    from eyelume.estimators.cornea_nee import (
        Receiver,
        irradiance_through_cornea,
        led_through_cornea,
    )
    from eyelume.kernels.bins import from_grid
    from eyelume.kernels.rng import next_uniform, side_uniform
    from eyelume.kernels.sampling import orthonormal_basis
    from eyelume.kernels.tables import Ray

    cs = compile_scene(eyelume.load_scene("vr-offaxis"))
    iris = cs.surface_names.index("iris")
    cam, leds, surfaces = cs.camera, cs.tables.leds, cs.tables.surfaces
    checked = 0
    for col, row in ((200, 200), (190, 205), (210, 195), (205, 210)):
        for dc in range(-30, 31, 2):
            xs, ys = from_grid(cs.tables.picture, col + dc + 0.5, row + 0.5)
            chief = aim_chief(cam, xs, ys)
            r = into_scene(cam, xs, ys, chief.qx, chief.qy)
            out = F._camera_branch(
                np.uint64(1),
                cs.tables,
                cam,
                Ray(r.x, r.y, r.z, r.dx, r.dy, r.dz),
                1.0,
                True,
                True,
                F.Scratch(
                    np.empty(8),
                    np.empty((F.ELEMENT_BRANCHES, 7)),
                    np.zeros(1, dtype=np.int64),
                    np.empty(cs.sf.shape[0]),
                ),
                -3.0,
            )
            v = out.vertex
            if v.s != iris:
                continue
            e1, e2 = orthonormal_basis(v.nx, v.ny, v.nz)
            rc = Receiver(v.x, v.y, v.z, v.nx, v.ny, v.nz, e1, e2)
            each = [led_through_cornea(surfaces, cam.cornea, iris, leds, k, rc) for k in range(8)]
            total = irradiance_through_cornea(surfaces, cam.cornea, iris, leds, rc)
            assert sum(1 for e in each if e > 0.0) >= 2
            assert total == pytest.approx(math.fsum(each), rel=1e-12)
            checked += 1
    assert checked >= 10
    state = stream_start(7, 3)
    u = [side_uniform(np.uint64(s), 0x1234) for s in range(1, 20_001)]
    assert 0.0 <= min(u) and max(u) < 1.0
    assert abs(np.mean(u) - 0.5) < 4 * math.sqrt(1 / 12 / len(u))
    assert side_uniform(state, 1) != side_uniform(state, 2)
    assert next_uniform(state) == next_uniform(state)  # side_uniform took nothing from it


def test_rel_error_is_judged_on_the_delivered_picture():
    """With a camera PSF the picture a render delivers is the traced one convolved, which
    averages neighbouring pixels' independent noise: a ``rel_error`` run stops when that
    picture's median skin pixel meets the target — the error the result reports — not the
    traced picture's (which would cost ~1/ΣK² as many samples)."""
    sc = eyelume.load_scene(
        "vr-offaxis",
        {"sensor.cols": 100, "sensor.rows": 100, "sensor.pixel_pitch_um": 12.0,
         "camera.ideal.f_number": 8.0},
    )  # fmt: skip
    r = eyelume.render(sc, eyelume.RenderOptions(estimator="fast", rel_error=0.006, seed=2))
    skin = r.region_stats()["skin"]["median_pixel_rel_error"]
    assert r.target_reached and skin <= 0.006
    assert r.rel_error_achieved == pytest.approx(skin, rel=1e-9)
    ((psf, traced_var),) = r.psf_parts
    assert psf.kernel.size > 1
    m = r.regions["skin"]
    traced = median_pixel_rel_error_of(r, traced_var, m)
    assert traced > 0.006, f"the traced picture met the target alone ({traced:.4f})"


def median_pixel_rel_error_of(r, traced_var, mask):
    """The traced picture's median skin error (its image is the delivered one deconvolved: use
    the delivered mean, which differs from the traced mean by the blur only)."""
    from eyelume.estimators.statistics import median_pixel_rel_error

    return median_pixel_rel_error(r.eye_image[mask], traced_var[mask], r.variance_dof)


@pytest.mark.parametrize("rel_error", [0.2, 0.004])
def test_pilot_skips_only_grids_that_could_not_be_chosen(paper_compiled, monkeypatch, rel_error):
    """The pilot does not trace a grid whose least cost (two sets) is not below the best choice
    so far: its choice is the one of tracing every grid (computed here as the pilot did before
    the skip), and the grids it traced are exactly those whose least cost beat the best so far."""
    from eyelume.estimators import fast_run
    from eyelume.estimators.statistics import median_pixel_rel_error

    cs = paper_compiled
    target = np.zeros((cs.picture.rows, cs.picture.cols), dtype=bool)
    target[20:45:2, 25:60:3] = True  # ~150 scattered pixels of the eye and skin
    seed, ratio = 3, 0.5
    idx = np.flatnonzero(target.reshape(-1)).astype(np.int64)
    costs = []
    for grid, n in fast_run.PILOT_OPTIONS:
        s1, s2 = np.zeros(idx.size), np.zeros(idx.size)
        F.camera_pass(seed, 0, n, cs.tables, cs.camera, grid, F.CameraSums(idx, s1, s2))
        mean = s1 / n
        var = np.maximum(s2 - n * mean**2, 0.0) / (n * (n - 1))
        err = median_pixel_rel_error(mean[mean > 0], var[mean > 0], n - 1) * math.sqrt(ratio)
        costs.append((max(2, math.ceil(n * (err / rel_error) ** 2)), grid))
    best, expect_traced = (fast_run.GRID_FINE, 2, math.inf), []
    for sets, grid in costs:
        if 2 * grid * grid < best[2]:
            expect_traced.append(grid)
        if sets * grid * grid < best[2]:
            best = (grid, sets, sets * grid * grid)
    traced = []
    real = F.camera_pass

    def spy(seed_, first, n_sets, tables, cam, grid, sums):
        traced.append(grid)
        return real(seed_, first, n_sets, tables, cam, grid, sums)

    monkeypatch.setattr(F, "camera_pass", spy)
    assert fast_run._pilot(cs, seed, target, rel_error, ratio) == best[:2]
    assert traced == expect_traced


def test_rel_error_on_a_picture_without_skin_is_judged_by_every_lit_pixel():
    """vr-offaxis's 3 µm pixels on a 100 × 100 sensor see the eye only, no skin: a ``rel_error``
    render says so (one warning) and is judged by the median pixel with signal, instead of going
    on to its cap with the skin's median never known (before: to 4096 samples per pixel, and the
    CLI's progress line ended in an OverflowError)."""
    from eyelume.errors import EyelumeWarning
    from eyelume.estimators.statistics import median_pixel_rel_error

    sc = eyelume.load_scene("vr-offaxis", {"sensor.cols": 100, "sensor.rows": 100})
    opt = eyelume.RenderOptions(estimator="fast", rel_error=0.02, seed=1, max_samples_per_pixel=64)
    with pytest.warns(EyelumeWarning, match="no skin pixel"):
        r = eyelume.render(sc, opt)
    assert not r.regions["skin"].any()
    m = r.eye_image > 0
    err = median_pixel_rel_error(r.eye_image[m], r.eye_image_variance[m], r.variance_dof)
    assert r.target_reached and err <= 0.02 and r.samples_per_pixel < 64
    assert r.rel_error_achieved == pytest.approx(err, rel=1e-9)


def test_over_cap_message_with_the_error_not_known():
    """The progress line for a target whose projection is not finite names no number."""
    from eyelume.estimators.fast_run import _over_cap

    said = []
    _over_cap(said.append, 0.01, math.inf, 64)
    _over_cap(said.append, 0.01, 100.4, 64)
    _over_cap(said.append, 1e-10, 5.335e17, 4)
    assert said == [
        "the target 0.01 needs an unknown number of samples per pixel, over the cap of 64: "
        "rendering to the cap",
        "the target 0.01 needs ~100 samples per pixel, over the cap of 64: rendering to the cap",
        "the target 1e-10 needs ~5.3e+17 samples per pixel, over the cap of 4: rendering to the "
        "cap",
    ]


def test_samples_needed_for_a_tiny_target_do_not_overflow():
    """(err / rel_error)² for a target of 1e-160 is beyond a float: inf, not OverflowError."""
    from eyelume.estimators.fast_run import _squared_ratio

    assert _squared_ratio(0.02, 0.01) == pytest.approx(4.0)
    assert _squared_ratio(0.02, 1e-160) == math.inf
    assert _squared_ratio(math.inf, 0.01) == math.inf
