"""A lens that forms no real image of the eye plane is refused; a sensor out of focus warned
about (issue 12)."""

from __future__ import annotations

import math
import warnings

import pytest
from typer.testing import CliRunner

import eyelume
from eyelume.cli import app
from eyelume.compile import compile_scene, lens_indices, lens_paraxial
from eyelume.errors import GeometryError
from eyelume.scene.focus import FocusWarning, focus

# a weak N-BK7 singlet (EFL ≈ 392 mm) with the eye plane 70 mm before it: inside its front
# focal length, so the image is virtual
SINGLET = (
    '[{radius_mm=400.0, thickness_mm=5.0, glass="N-BK7", stop=true},'
    " {radius_mm=-400.0, thickness_mm=100.0}]"
)


def test_default_lens_is_in_focus():
    """The paper's lens at 850 nm: paraxial image 199.45 mm behind the last vertex, sensor at
    200.46 mm; N_w = 4.00 and 46 mm / 87 = 0.529 mm pixels give ± 2.11 mm of depth of focus."""
    scene = eyelume.load_scene("paper2005")
    with warnings.catch_warnings():
        warnings.simplefilter("error", FocusWarning)
        cs = compile_scene(scene)
    par = lens_paraxial(scene, cs.lens_indices)
    f = focus(scene, par, cs.stop_index, float(cs.lf[cs.stop_index, 3]))
    assert f.image_distance_mm == pytest.approx(199.45, abs=0.01)
    assert f.working_f_number == pytest.approx(4.00, abs=0.01)
    assert f.pixel_mm == pytest.approx(46.0 / 87)
    assert f.depth_of_focus_mm == pytest.approx(f.working_f_number * 46.0 / 87)
    assert abs(f.defocus_mm) < f.depth_of_focus_mm


def test_virtual_image_is_refused():
    scene = eyelume.load_scene("paper2005", {"lens.surfaces": SINGLET})
    idx, _ = lens_indices(scene)
    par = lens_paraxial(scene, idx)
    # thin-lens check: EFL = 1 / ((n − 1)(2/400)) with n(850 nm) = 1.50984
    assert par.efl == pytest.approx(1 / ((idx[1] - 1) * 2 / 400), rel=0.01)
    assert par.image_distance(70.0) < 0  # virtual
    with pytest.raises(GeometryError, match=r"lens.*no real image.*virtual") as info:
        compile_scene(scene)
    assert "\n" not in str(info.value)


def test_virtual_image_cli_one_line_exit_2():
    res = CliRunner().invoke(app, ["info", "--set", f"lens.surfaces={SINGLET}"])
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and "no real image" in lines[0] and "Traceback" not in res.output


def test_sensor_far_from_focus_warns_with_the_numbers():
    """N-BK7 in place of BSM24 in the first element: the image moves to 207.76 mm, 7.3 mm from
    the sensor, beyond ± N_w·p."""
    scene = eyelume.load_scene("paper2005", {"lens.surfaces.0.glass": "N-BK7"})
    with pytest.warns(FocusWarning) as record:
        cs = compile_scene(scene)
    msg = str(record[0].message)
    assert "lens.surfaces.10.thickness_mm = 200.46" in msg and "depth of focus" in msg, msg
    par = lens_paraxial(scene, cs.lens_indices)
    f = focus(scene, par, cs.stop_index, float(cs.lf[cs.stop_index, 3]))
    assert abs(f.defocus_mm) > f.depth_of_focus_mm
    assert f"{abs(f.defocus_mm):.3g} mm" in msg
    assert math.isfinite(f.image_distance_mm)


def test_sensor_far_from_focus_cli_warns_one_line_exit_0():
    res = CliRunner().invoke(app, ["info", "--json", "--set", "lens.surfaces.0.glass=N-BK7"])
    assert res.exit_code == 0, res.output
    warn = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(warn) == 1 and warn[0].startswith("warning: lens: the sensor"), res.stderr
