"""The eyelash fringe (``face.lashes``; ``kernels/geometry.py`` ``SHAPE_LASHES``) against its
closed form; its scene validation; glints it hides in the truth; its pixels' region.

Closed form: a uniform backdrop seen from a point through the fringe. A ray that crosses the
fringe's cone once, at the distance r from its axis and inside the lashes' span, meets a lash
with probability 2 h / (r · pitch) (h the half-width, pitch the lashes' angular spacing) when
its crossing azimuth is uniform over a pitch — as it is, to far better than the statistics,
for rays aimed at uniformly random points of a backdrop spanning ~100 pitches. So the number of
blocked rays K is a sum of independent Bernoulli(p_i) with p_i from the crossing computed here
in NumPy (independently of the kernel): (K − Σp) / √Σp(1 − p) is ~N(0, 1).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from eyelume.analysis.regions import region_masks
from eyelume.analysis.truth import eye_truth
from eyelume.compile import compile_scene, lash_fringe
from eyelume.errors import SceneError
from eyelume.estimators.fast_run import primary_surface_map
from eyelume.kernels import geometry as G
from eyelume.scene.io import apply_overrides, load_scene, validate_scene

LASHES = {
    "face.lashes.enabled": True,
    "face.lashes.count": 80,
    "face.lashes.width_mm": 0.12,
    "face.lashes.length_mm": 10.0,
}


def _crossings(fr, p, d):
    """Per ray (rows of p, d): the crossing distances r from the axis of every valid crossing
    of the fringe's cone (z in its range, azimuth inside the span), NaN where none."""
    axis, fwd = fr["axis"], fr["forward"]
    rot = np.stack([fwd, np.cross(axis, fwd), axis])
    q = (p - fr["apex"]) @ rot.T
    u = d @ rot.T
    m2 = fr["slope"] ** 2
    a = u[:, 0] ** 2 + u[:, 1] ** 2 - m2 * u[:, 2] ** 2
    b = 2 * (q[:, 0] * u[:, 0] + q[:, 1] * u[:, 1] - m2 * q[:, 2] * u[:, 2])
    c = q[:, 0] ** 2 + q[:, 1] ** 2 - m2 * q[:, 2] ** 2
    disc = np.sqrt(np.maximum(b * b - 4 * a * c, 0.0))
    out = np.full((len(p), 2), np.nan)
    for k, sign in enumerate((-1.0, 1.0)):
        t = (-b + sign * disc) / (2 * a)
        h = q + t[:, None] * u
        r = np.hypot(h[:, 0], h[:, 1])
        psi = np.arctan2(h[:, 1], h[:, 0])
        ok = (
            (b * b - 4 * a * c >= 0)
            & (t > 0)
            & (h[:, 2] >= fr["z_range"][0])
            & (h[:, 2] <= fr["z_range"][1])
            & (np.abs(psi) <= 0.5 * fr["count"] * fr["pitch"])
        )
        out[ok, k] = r[ok]
    return out


@pytest.mark.parametrize("preset", ["paper2005", "vr-offaxis"])
def test_blocked_fraction_of_a_backdrop_is_the_lashes_covered_fraction(preset):
    scene = apply_overrides(load_scene(preset), LASHES)
    cs = compile_scene(scene)
    fr = lash_fringe(scene)
    s = cs.surface_names.index("eyelashes")
    assert cs.si[s, G.SHAPE] == G.SHAPE_LASHES
    # the table is in the camera frame: take the fringe there
    fr = dict(fr)
    fr["apex"] = cs.frame.point(fr["apex"])
    fr["axis"] = cs.frame.vector(fr["axis"])
    fr["forward"] = cs.frame.vector(fr["forward"])
    rng = np.random.default_rng(7)
    n = 60_000
    eye = cs.frame.point(np.array([0.0, -14.0, 30.0]))  # in front of and below the eye
    back = np.stack(
        [rng.uniform(-16, 16, n), rng.uniform(0.0, 22.0, n), np.full(n, -10.0)], 1
    )  # a backdrop behind the lashes
    back = cs.frame.point(back)
    d = back - eye
    d /= np.linalg.norm(d, axis=1)[:, None]
    p = np.broadcast_to(eye, d.shape)
    cross = _crossings(fr, p, d)
    once = np.isfinite(cross).sum(1) == 1
    assert once.sum() > 20_000  # most rays cross the fringe
    r = np.nanmax(cross[once], axis=1)
    prob = 2 * fr["half_width"] / (r * fr["pitch"])
    assert prob.max() < 1
    hits = np.array(
        [G.intersect_surface(cs.sf, cs.si, s, *eye, *dd, math.inf) > 0.0 for dd in d[once]]
    )
    k, mean, var = hits.sum(), prob.sum(), (prob * (1 - prob)).sum()
    z = (k - mean) / math.sqrt(var)
    assert abs(z) < 4.0, f"{k} blocked against {mean:.0f} ± {math.sqrt(var):.0f}"
    # rays that miss the fringe's cone (or cross outside its span or length) pass
    never = np.isnan(cross).all(1)
    assert never.sum() > 1000
    assert not any(
        G.intersect_surface(cs.sf, cs.si, s, *eye, *dd, math.inf) > 0.0 for dd in d[never][:2000]
    )


def test_lashes_are_off_by_default_and_leave_the_table_alone():
    scene = load_scene("paper2005")
    assert not scene.face.lashes.enabled
    cs = compile_scene(scene)
    assert "eyelashes" not in cs.surface_names
    assert cs.sf.shape[1] == G.N_FLOAT


@pytest.mark.parametrize(
    ("over", "words"),
    [
        ({"face.lashes.lid": "brow"}, "lashes need a sphere"),
        ({"face.lashes.lid": "upper lid"}, "names no face tissue"),
        ({"face.lashes.count": 400}, "overlap at the margin"),
        ({"face.lashes.width_mm": -0.1}, "width_mm"),
        ({"face.lashes.tilt_deg": 95.0}, "tilt_deg"),
        ({"face.lashes.reflectance": 1.5}, "reflectance"),
        ({"face.lashes.length_mm": float("nan")}, "length_mm"),
    ],
)
def test_impossible_lashes_are_refused_in_one_line(over, words):
    with pytest.raises(SceneError) as err:
        validate_scene(_dump_with(over))
    msg = str(err.value)
    assert words in msg and "\n" not in msg


def _dump_with(over):
    data = load_scene("paper2005").model_dump(mode="json")
    lashes = data["face"]["lashes"]
    lashes["enabled"] = True
    for key, value in over.items():
        lashes[key.split(".")[-1]] = value
    return data


def test_a_glint_behind_the_lashes_is_hidden_in_the_truth():
    """vr-offaxis (its camera below the eye) with coarse lashes: the top LED's light reflected
    by the cornea toward it crosses the upper lid's fringe; its glint, seen without lashes, is
    hidden with them, and only glints behind the fringe are: an LED (or the camera) some
    straight line of which to the cornea's central 4 mm crosses the fringe's cone inside the
    lashes' span and length."""
    base = load_scene("vr-offaxis")
    coarse = {**LASHES, "face.lashes.count": 60, "face.lashes.width_mm": 0.3}
    without = eye_truth(compile_scene(base))
    scene = apply_overrides(base, coarse)
    cs = compile_scene(scene)
    with_lashes = eye_truth(cs)
    assert all(g["visible"] for g in without["glints"])
    hidden = [g["led"] for g in with_lashes["glints"] if not g["visible"]]
    assert hidden
    fr = lash_fringe(scene)
    # points of the cornea's central 4 mm (a sphere of its apical radius about the apex)
    x, y = np.meshgrid(np.linspace(-4, 4, 41), np.linspace(-4, 4, 41))
    x, y = x[x**2 + y**2 <= 16], y[x**2 + y**2 <= 16]
    rc = scene.eye.surfaces[0].radius_mm
    cornea = np.stack([x, y, -(x**2 + y**2) / (rc + np.sqrt(rc**2 - x**2 - y**2))], 1)

    def behind(point):
        d = cornea - point
        d /= np.linalg.norm(d, axis=1)[:, None]
        return bool(np.isfinite(_crossings(fr, np.broadcast_to(point, d.shape), d)).any())

    leds = cs.frame.world_point(cs.led.points)
    camera_behind = behind(np.asarray(scene.camera.position_mm))
    for k in hidden:
        assert camera_behind or behind(leds[k]), k
    for g in with_lashes["glints"]:
        if not g["visible"]:
            assert "lashes" in g["reason"]


def test_lashes_seen_are_labelled_skin():
    """The regions count a pixel whose chief ray first meets a lash as skin (the lid's)."""
    scene = apply_overrides(
        load_scene("vr-offaxis"),
        {
            **LASHES,
            "face.lashes.count": 60,
            "face.lashes.width_mm": 0.3,
            "sensor.cols": 100,
            "sensor.rows": 100,
            "sensor.width_mm": 1.2,  # the preset's 400 x 400 field at a quarter of the pixels
            "sensor.height_mm": 1.2,
        },
    )
    cs = compile_scene(scene)
    labels, _ = primary_surface_map(cs)
    lash = labels == cs.surface_names.index("eyelashes")
    assert lash.sum() > 20  # the lashes are in view
    masks = region_masks(cs)
    assert masks["skin"][lash].all()


def test_cli_refuses_overlapping_lashes_in_one_line(tmp_path):
    from typer.testing import CliRunner

    from eyelume.cli import app

    res = CliRunner().invoke(
        app,
        ["render", "--scene", "vr-offaxis", "--out", str(tmp_path / "out")]
        + ["--set", "face.lashes.enabled=true", "--set", "face.lashes.count=400"],
        prog_name="eyelume",
    )
    assert res.exit_code == 2, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and "lashes.count = 400" in lines[0] and "overlap" in lines[0]
    assert not (tmp_path / "out" / "eye_image.npy").exists()
