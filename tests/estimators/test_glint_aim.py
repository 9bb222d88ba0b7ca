"""Light paths aimed at each glint's specular point (``CameraTables.glint_aim``).

The glints are formed by light paths alone (LEDs are points), and a light path drawn over the
whole cornea reaches the camera's entrance pupil after the cornea's reflection in ~1e-4 of its
draws on vr-offaxis. A share of each LED's draws now goes into the narrow cone about the
direction to the cornea point that reflects the LED into the pupil's centre, weighted by the
mixture's density. These tests check the cone (its axis reflects into the pupil's centre, it
holds every direction whose reflection passes through the pupil) and that the mixture estimates
the same glints as the whole-cornea draws alone (z-scores of each glint's power between the two,
independent seeds).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from eyelume.compile import compile_scene
from eyelume.estimators import fast as F
from eyelume.estimators.fast_run import _Run
from eyelume.kernels import geometry as G
from eyelume.kernels.sampling import about_axis, uniform_cone
from eyelume.kernels.tables import G_AX, G_AZ, G_COS, G_P
from eyelume.scene.io import load_scene


@pytest.fixture(scope="module")
def vr():
    return compile_scene(load_scene("vr-offaxis"))


def _pupil_crossing(cs, p, d):
    """(x, y) where the LED's ray along ``d``, reflected by the anterior cornea, crosses the
    entrance pupil's plane toward the camera, or None (written here from the surface table)."""
    sf, si = cs.tables.surfaces.sf, cs.tables.surfaces.si
    s, t = G.nearest_hit(sf, si, *p, *d)
    if s != cs.camera.cornea:
        return None
    x = p + t * d
    n = np.array(G.surface_normal(sf, si, s, *x))
    r = d - 2.0 * (d @ n) * n
    if r[2] <= 0.0:
        return None
    ep_z = cs.camera.entrance_pupil_z
    return (x + (ep_z - x[2]) / r[2] * r)[:2]


def test_each_glint_cone_is_aimed_at_the_pupil_and_holds_its_preimage(vr):
    ga = vr.camera.glint_aim
    assert (ga[:, G_P] > 0).all(), "vr-offaxis: every LED's glint reaches the lens"
    ep_r = vr.first_order.entrance_pupil_radius
    rng = np.random.default_rng(4)
    for k, p in enumerate(vr.led.points):
        axis = ga[k, G_AX : G_AZ + 1]
        hit = _pupil_crossing(vr, p, axis)
        assert hit is not None and math.hypot(*hit) < 1e-5, hit
        cos_a = ga[k, G_COS]
        assert math.degrees(math.acos(cos_a)) < 1.0  # narrow: ~1e-4 of the cornea's cone
        # directions in a cone 3 × as wide: every one whose reflection passes through the
        # entrance pupil lies in the aimed cone, and the aimed cone is not much wider
        half = 3.0 * math.acos(cos_a)
        crossings = []
        for _ in range(3000):
            lx, ly, lz = uniform_cone(rng.random(), rng.random(), math.cos(half))
            d = np.array(about_axis(lx, ly, lz, *axis))
            q = _pupil_crossing(vr, p, d)
            if q is not None:
                crossings.append((math.hypot(*q), float(d @ axis) >= cos_a))
        r, aimed = np.array(crossings).T
        through = r <= ep_r
        assert through.sum() > 50
        assert aimed[through].all(), "a direction through the pupil outside the aimed cone"
        # and a fair share of the aimed cone's draws pass through the pupil (~26 %: the cone is
        # 1.15 × 1.25 the linearised preimage's widest angle, which is an ellipse), where a
        # draw over the whole cornea does in ~1e-4
        assert through[aimed == 1].mean() > 0.15


@pytest.mark.slow
def test_aimed_and_whole_cornea_draws_estimate_the_same_glints(vr):
    """The light paths' picture summed over a window about each glint (7 × 7 pixels about
    where the aimed run's glint of that LED is brightest): 1.6 M paths drawn over the whole
    cornea (p = 0) against 400 k with the aim, independent seeds; z = Δ / √(var₀ + var₁) per
    window, Σz² inside χ²'s central 99.8 % (one dof per LED). A path deposits in one pixel, so
    a window's variance is (Σ c² / m − (Σ c / m)²) / (m − 1) from the per-pixel sums."""
    p_on = float(vr.camera.glint_aim[0, G_P])
    assert p_on > 0
    runs = []
    for p_aim, paths, seed in ((0.0, 1_600_000, 21), (p_on, 400_000, 22)):
        cam = vr.camera._replace(glint_aim=vr.camera.glint_aim.copy())
        cam.glint_aim[:, G_P] = p_aim
        run = _Run(vr, 2, seed)  # its fixed-point units follow the aimed draws' (p_on > 0)
        F.light_pass(seed, 0, paths, vr.tables, cam, run.tally())
        img = run.light.sum(axis=0).astype(float) * run.q / paths
        sq = run.light_sq.sum(axis=0).astype(float) * run.q2 / paths
        led = run.led.sum(axis=0)
        runs.append((img, sq, led, paths))
    led_aimed = runs[1][2]
    z, rel = [], []
    for k in range(led_aimed.shape[0]):
        r0, c0 = np.unravel_index(np.argmax(led_aimed[k]), led_aimed[k].shape)
        win = (slice(max(r0 - 3, 0), r0 + 4), slice(max(c0 - 3, 0), c0 + 4))
        means, variances = [], []
        for img, sq, _, m in runs:
            mu = img[win].sum()
            means.append(mu)
            variances.append(max(sq[win].sum() - mu * mu, 0.0) / (m - 1))
        assert min(means) > 0, (k, means)
        z.append((means[0] - means[1]) / math.sqrt(sum(variances)))
        rel.append([math.sqrt(v) / mu for mu, v in zip(means, variances, strict=True)])
    chi2 = float(np.sum(np.square(z)))
    lo, hi = stats.chi2.ppf([0.001, 0.999], len(z))
    assert lo < chi2 < hi, (chi2, z)
    # and from a quarter of the paths the aim knows each glint's power better
    rel = np.array(rel)
    assert (rel[:, 1] < rel[:, 0]).all(), rel
