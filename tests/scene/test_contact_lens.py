"""A contact lens on the eye (issue 14; scene/eye.py::with_contact_lens): a thin shell of
thickness t concentric with the anterior cornea, its front of index n.

* the glint surface reflects the closed-form Fresnel value at normal incidence
  ((n − 1)/(n + 1))², read back from the compiled surface table by the kernels' interface;
* the eye stays where it was (the posterior cornea, the rotation centre) and the front moves t
  toward the world, its radius R + t;
* applying it twice is applying it once; no lens, no change;
* the forward estimator's ledger is exact with it (every emitted watt accounted for).
"""

from __future__ import annotations

import numpy as np
import pytest

import eyelume
from eyelume.compile import compile_scene, eye_point
from eyelume.kernels.interact import interface_at
from eyelume.scene.eye import with_contact_lens

LENS = {"eye.contact_lens": {"refractive_index": 1.50, "thickness_mm": 0.1}}


def test_glint_surface_reflects_the_fresnel_closed_form():
    for n in (1.44, 1.50):
        scene = eyelume.load_scene("paper2005", {"eye.contact_lens": {"refractive_index": n}})
        cs = compile_scene(scene)
        s = cs.surface_names.index("anterior cornea")
        r = interface_at(cs.sf, cs.si, s, -1.0).reflectance
        assert r == pytest.approx(((n - 1) / (n + 1)) ** 2, rel=1e-12)
    assert ((1.5 - 1) / 2.5) ** 2 == pytest.approx(0.04)  # against the tear film's 2.1 %


def test_the_shell_sits_on_the_cornea_and_the_eye_stays():
    plain = eyelume.load_scene("paper2005")
    fitted = with_contact_lens(eyelume.load_scene("paper2005", LENS))
    t = 0.1
    r0 = plain.eye.surfaces[0]
    assert fitted.eye.surfaces[0].radius_mm == pytest.approx(r0.radius_mm + t)
    assert fitted.eye.contact_lens is None
    assert fitted.eye.cornea_reflectance == pytest.approx(0.04)
    # the posterior corneal vertex, the crystalline lens and the rotation centre: same world point
    depth = 0.0
    for j, surf in enumerate(plain.eye.surfaces[:-1]):
        depth += surf.thickness_mm
        a = eye_point(plain, [0.0, 0.0, -depth], 0.0, 0.0)  # eye frame: z toward the world
        b = eye_point(fitted, [0.0, 0.0, -depth - t], 0.0, 0.0)
        assert np.allclose(a, b, atol=1e-12), j
    # the front vertex t in front of the bare cornea's
    assert eye_point(fitted, [0.0, 0.0, 0.0], 0.0, 0.0)[2] == pytest.approx(t)
    # and turned with the gaze about the same centre
    a = eye_point(plain, [0.0, 0.0, -3.6], 20.0, -10.0)
    b = eye_point(fitted, [0.0, 0.0, -3.6 - t], 20.0, -10.0)
    assert np.allclose(a, b, atol=1e-12)
    # the eyeball (the sclera sphere through the limbus) stays: its centre t deeper in the frame
    from eyelume.scene.eye import limbus_geometry

    assert limbus_geometry(fitted.eye)[2] == pytest.approx(limbus_geometry(plain.eye)[2] + t)
    assert with_contact_lens(fitted) is fitted
    assert with_contact_lens(plain) is plain


def test_forward_ledger_exact_and_glints_seen_with_a_contact_lens():
    scene = eyelume.load_scene("paper2005", LENS)
    cs = compile_scene(scene)
    r = eyelume.render(cs, eyelume.RenderOptions(estimator="forward", rays=1_000_000))
    assert sum(r.ledger.values()) == pytest.approx(r.emitted_w, rel=1e-12)
    from eyelume.analysis.truth import eye_truth

    assert (
        eye_truth(cs)["glints_visible"]
        == eye_truth(compile_scene(eyelume.load_scene("paper2005")))["glints_visible"]
    )
