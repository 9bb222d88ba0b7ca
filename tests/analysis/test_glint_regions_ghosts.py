"""Issue 14 (fresh user): a glint region holds its LED's corneal glint only, never the LED's
spectacle ghosts (LED → spectacle → camera), which the LED's glint image also carries (every
path that met no Lambertian face) and which are often far brighter than the glint: with
``glint k`` thresholded at 5 % of the image's peak, the ghost was the peak, ``glint k`` took
the ghost's pixels and ``reflection`` was left nearly empty."""

from __future__ import annotations

import numpy as np

from eyelume.analysis.regions import GLINT_FRACTION, with_glints


def _blob(shape, x, y, peak, sigma=0.8):
    r, c = np.mgrid[: shape[0], : shape[1]]
    g = peak * np.exp(-((c - x) ** 2 + (r - y) ** 2) / (2 * sigma**2))
    return np.where(g >= 1e-3 * peak, g, 0.0)  # a finite support, as a traced image has


def _masks(shape, reflection):
    base = np.zeros(shape, dtype=bool)
    base[:, : shape[1] // 2] = True
    return {"skin": base, "sclera": ~base, "reflection": reflection}


def test_the_ghost_brighter_than_the_glint_stays_in_reflection():
    """LED 0: a corneal glint at (30, 20) and a ghost 200× brighter at (8, 6) whose truth
    disc (``reflection``) covers its core but not all of its tail; LED 1: a glint alone.
    ``glint 0`` is the glint's pixels (≥ 5 % of the glint's own peak) — none of the ghost's,
    its core or its tail; ``reflection`` keeps every ghost pixel it had."""
    shape = (40, 50)
    r, c = np.mgrid[: shape[0], : shape[1]]
    reflection = (c - 8) ** 2 + (r - 6) ** 2 <= 1.5**2
    glint = _blob(shape, 30.0, 20.0, 1.0)
    ghost = _blob(shape, 8.0, 6.0, 200.0)
    images = np.stack([glint + ghost, _blob(shape, 20.0, 30.0, 2.0)])
    masks = _masks(shape, reflection)

    out = with_glints(masks, images, [(30.2, 19.9), (20.0, 30.0)])
    assert np.array_equal(out["glint 0"], glint >= GLINT_FRACTION * glint.max())
    assert not np.any(out["glint 0"] & (ghost > 0))
    assert np.array_equal(out["reflection"], reflection)
    assert np.array_equal(out["glint 1"], images[1] >= GLINT_FRACTION * images[1].max())
    # the old rule (the image's pixels >= 5 % of its peak) took the ghost, not the glint
    old = images[0] >= GLINT_FRACTION * images[0].max()
    assert np.any(old & reflection) and not np.any(old & (glint > 0) & ~(ghost > 0))
    # glint pixels leave the other regions; reflection pixels never become a glint's
    for name in ("skin", "sclera"):
        assert not np.any(out[name] & (out["glint 0"] | out["glint 1"]))


def test_no_visible_glint_no_region_and_nearest_part_when_off_the_lit_pixels():
    """An LED without a visible corneal glint (centre None) gets an empty region even if its
    ghost is lit; a true centre a pixel off the lit support picks the nearest lit part."""
    shape = (30, 30)
    ghost = _blob(shape, 5.0, 5.0, 50.0)
    glint = _blob(shape, 20.0, 20.0, 1.0, sigma=0.5)
    images = np.stack([ghost, glint])
    nothing = np.zeros(shape, dtype=bool)
    out = with_glints(_masks(shape, nothing), images, [None, (23.0, 20.0)])
    assert not out["glint 0"].any()
    assert np.array_equal(out["glint 1"], glint >= GLINT_FRACTION * glint.max())


def test_without_centres_the_rule_is_the_fraction_of_the_peak():
    """No elements (no ``centres``, no ``reflection``): unchanged, ≥ 5 % of each image's peak."""
    shape = (20, 20)
    img = _blob(shape, 10.0, 10.0, 3.0)[None]
    masks = {"skin": np.ones(shape, dtype=bool)}
    out = with_glints(masks, img)
    assert np.array_equal(out["glint 0"], img[0] >= GLINT_FRACTION * img[0].max())
    assert not np.any(out["skin"] & out["glint 0"])


# the fresh user's scene: paper2005-integrated with a 50/50 beamsplitter in the hot mirror's
# place and vr-offaxis-glasses' spectacle lens (its 4 visible ghosts are 50–140 × the glints)
_FRESH_ELEMENTS = [
    {
        "kind": "lens",
        "name": "eyepiece",
        "position_mm": [0, 0, 30],
        "direction": [0, 0, 1],
        "thickness_mm": 5.3,
        "glass": "N-BK7",
        "semi_diameter_mm": 12.7,
        "front": {
            "radius_mm": 25.75,
            "coating": {"model": "fixed", "reflectance": 0.005, "transmittance": 0.995},
        },
        "back": {"coating": {"model": "fixed", "reflectance": 0.005, "transmittance": 0.995}},
    },
    {
        "kind": "mirror",
        "name": "hot mirror",
        "position_mm": [0, 0, 55.3],
        "direction": [0.70710678, 0, -0.70710678],
        "semi_diameter_mm": 18.0,
        "front": {"coating": {"model": "fixed", "reflectance": 0.5, "transmittance": 0.5}},
    },
    {
        "kind": "lens",
        "name": "spectacle",
        "position_mm": [0.0, -0.278, 14.02],
        "direction": [0.0, 0.13917, -0.99027],
        "thickness_mm": 2.0,
        "glass": "CR-39",
        "semi_diameter_mm": 20.0,
        "front": {"radius_mm": 124.5},
        "back": {"radius_mm": 70.92},
    },
]


def test_fresh_users_spectacle_ghosts_land_in_reflection_not_in_a_glint():
    """A 40 × 30 render (same field) of the fresh user's scene, 2 samples per pixel: every
    visible ghost's centre pixel is in ``reflection`` and in no ``glint k``; no glint region
    has a reflection pixel; each non-empty ``glint k`` lies within 1.5 px of LED k's true
    corneal glint; and the ghosts were drawn (the reflection region carries more power than
    all glint regions together — the ghosts are 50–140 × the glints), so the test is the
    case the old rule failed (it gave LED 3's region the ghost pixels (19, 23), (20, 23))."""
    import eyelume
    from eyelume.analysis.truth import eye_truth
    from eyelume.compile import compile_scene

    scene = eyelume.load_scene(
        "paper2005-integrated",
        {"elements": _FRESH_ELEMENTS, "sensor.cols": 40, "sensor.rows": 30},
    )
    cs = compile_scene(scene)
    truth = eye_truth(cs)
    ghosts = [g for g in truth["ghosts"] if g["visible"]]
    assert len(ghosts) == 4
    result = eyelume.render(cs, eyelume.RenderOptions(samples_per_pixel=2, seed=1))
    regions = result.regions
    glints = [regions[f"glint {k}"] for k in range(len(truth["glints"]))]
    for g in ghosts:
        x, y = (int(round(v)) for v in g["centre_px"])
        assert regions["reflection"][y, x], g
        assert not any(m[y, x] for m in glints), g
    r, c = np.mgrid[:30, :40]
    for k, m in enumerate(glints):
        assert not np.any(m & regions["reflection"]), k
        if m.any():
            x, y = truth["glints"][k]["centre_px"]
            assert np.all(np.hypot(c[m] - x, r[m] - y) <= 1.5), (k, np.argwhere(m))
    assert sum(m.any() for m in glints) >= 3
    image = result.eye_image
    assert image[regions["reflection"]].sum() > sum(image[m].sum() for m in glints)
