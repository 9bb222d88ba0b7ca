"""Optical elements in the scene (issue 14, first step): lenses, plates and mirrors placed by a
pose, compiled into the surface table the forward estimator traces, checked against closed forms.

* a plate's Fresnel reflectance at normal incidence is ((n − 1)/(n + 1))² per surface, n from
  the glass catalog at the scene's wavelength;
* a ray through a plate leaves parallel to itself, displaced sideways by
  t sin(θ − θ′)/cos θ′ (Snell), so a point seen through it at small angles appears t(1 − 1/n)
  nearer;
* a plane mirror: the eye-plane irradiance of an LED aimed at it is that of its mirror image
  (the emission point and axis mirrored in the mirror's plane), bin by bin within the forward
  estimate's multinomial noise;
* the forward ledger is exact with elements, and a mirror absorbing A = 1 − R − T of what
  reaches it files N·A·P(hit) rays under its own entry within binomial noise;
* bad elements are refused with one line, exit 2.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from scipy import stats
from typer.testing import CliRunner

import eyelume
from eyelume.cli import app
from eyelume.compile import compile_scene, element_label, element_light_shares
from eyelume.errors import InputFileError, SceneError
from eyelume.estimators.forward import trace_forward
from eyelume.kernels import geometry as G
from eyelume.kernels.interact import interface_at, refract
from eyelume.layout import system_sections
from eyelume.scene.glass import load_catalog
from eyelume.scene.sources import relative_intensity

runner = CliRunner()

PLATE = {
    "kind": "plate",
    "name": "window",
    "position_mm": [0.0, 0.0, 20.0],
    "thickness_mm": 3.0,
    "glass": "N-BK7",
    "semi_diameter_mm": 18.0,
}


def _scene(elements, **overrides):
    return eyelume.load_scene("paper2005", {"elements": elements, **overrides})


def _rows(cs, k: int = 0) -> list[int]:
    label = element_label(k, cs.scene.elements[k])
    return [s for s, n in enumerate(cs.surface_names) if n.startswith(label)]


def _n_bk7(wavelength_nm: float = 850.0) -> float:
    return float(load_catalog()["N-BK7"].index(wavelength_nm))


def test_plate_compiles_to_two_interfaces_and_an_edge_with_fresnel_at_normal_incidence():
    cs = compile_scene(_scene([PLATE]))
    front, back, edge = _rows(cs)
    n = _n_bk7()
    assert cs.si[front, G.ACTION] == G.ACT_REFRACT and cs.si[front, G.FRESNEL] == 1
    assert (cs.sf[front, G.N_A], cs.sf[front, G.N_B]) == (1.0, n)
    assert (cs.sf[back, G.N_A], cs.sf[back, G.N_B]) == (n, 1.0)
    assert cs.si[edge, G.SHAPE] == G.SHAPE_CYLINDER and cs.si[edge, G.ACTION] == G.ACT_OPAQUE
    r0 = ((n - 1.0) / (n + 1.0)) ** 2
    for s in (front, back):
        for cos_d in (-1.0, 1.0):  # from either side
            f = interface_at(cs.sf, cs.si, s, cos_d)
            assert f.reflectance == pytest.approx(r0, rel=1e-12)
            assert f.absorptance == 0.0
    assert "element 0 (window)" in cs.tallies


def _through(cs, x, y, z, dx, dy, dz):
    """Follow a ray through the compiled table, always refracting (the transmitted branch the
    forward estimator takes with probability T), until it leaves the element's rows."""
    rows = set(_rows(cs))
    for _ in range(4):
        s, t = G.nearest_hit(cs.sf, cs.si, x, y, z, dx, dy, dz)
        if s not in rows:
            return x, y, z, dx, dy, dz
        x, y, z = x + t * dx, y + t * dy, z + t * dz
        nx, ny, nz = G.surface_normal(cs.sf, cs.si, s, x, y, z)
        f = interface_at(cs.sf, cs.si, s, dx * nx + dy * ny + dz * nz)
        ok, dx, dy, dz = refract(dx, dy, dz, nx, ny, nz, f.n1 / f.n2)
        assert ok
    raise AssertionError("the ray did not leave the plate")


@pytest.mark.parametrize("theta_deg", [0.05, 10.0, 30.0])
def test_a_ray_through_a_plate_is_displaced_as_snell_says(theta_deg):
    """From a point on the eye's axis at z = 5 mm (in front of the cornea) toward the camera at
    angle θ: the ray leaves parallel, displaced by d = t sin(θ − θ′)/cos θ′; traced back, it
    meets the axis t (1 − 1/n) nearer the plate at small angles (the apparent shift of what is
    seen through it)."""
    t_mm, n = PLATE["thickness_mm"], _n_bk7()
    cs = compile_scene(_scene([PLATE]))
    th = math.radians(theta_deg)
    d0 = np.array([0.0, math.sin(th), math.cos(th)])
    p0 = np.array([0.0, 0.0, 5.0])
    x, y, z, dx, dy, dz = _through(cs, *p0, *d0)
    np.testing.assert_allclose([dx, dy, dz], d0, atol=1e-12)
    th_t = math.asin(math.sin(th) / n)
    d_expected = t_mm * math.sin(th - th_t) / math.cos(th_t)
    # distance of the exit ray's line from the entry ray's line
    offset = np.cross(np.array([x, y, z]) - p0, d0)
    assert np.linalg.norm(offset) == pytest.approx(d_expected, rel=1e-9, abs=1e-12)
    if theta_deg < 1.0:  # paraxial: the apparent source on the axis
        z_apparent = z - y * dz / dy
        assert z_apparent - p0[2] == pytest.approx(t_mm * (1 - 1 / n), rel=1e-5)


def _led_irradiance_flux(src, axis, i0, f, plane, weight=None) -> np.ndarray:
    """Flux per eye-plane bin (W) of a point LED at ``src`` with axis ``axis`` by 16 × 16
    Gauss–Legendre quadrature of I₀ f(α) w(cos β) cos β / r² (as
    tests/estimators/test_led_closed_form; ``weight`` w, default 1)."""
    w, h, nc, nr = plane.width_mm, plane.height_mm, plane.cols, plane.rows
    g, gw = np.polynomial.legendre.leggauss(16)
    flux = np.zeros((nr, nc))
    bw, bh = w / nc, h / nr
    for row in range(nr):
        y0 = h / 2 - (row + 1) * bh
        for col in range(nc):
            x0 = -w / 2 + col * bw
            xs, ys = np.meshgrid(x0 + (g + 1) * bw / 2, y0 + (g + 1) * bh / 2)
            dx, dy, dz = xs - src[0], ys - src[1], -src[2]
            r = np.sqrt(dx * dx + dy * dy + dz * dz)
            cos_a = (dx * axis[0] + dy * axis[1] + dz * axis[2]) / r
            alpha = np.arccos(np.clip(cos_a, -1, 1))
            inten = np.where(alpha <= math.pi / 2, i0 * f(np.minimum(alpha, math.pi / 2)), 0.0)
            if weight is not None:
                inten = inten * weight(src[2] / r)
            flux[row, col] = np.einsum("i,j,ij->", gw, gw, inten * (src[2] / r) / r**2)
            flux[row, col] *= bw * bh / 4
    return flux


#: A dark eye and no face: nothing sends light back to the mirror, so the eye plane sees the
#: LED's direct light and its mirror image only.
DARK = {
    "face.enabled": "false",
    "eye.cornea_reflection": '"fixed"',
    "eye.cornea_reflectance": 0.0,
    "eye.sclera_reflectance": 0.0,
    "eye.iris_reflectance": 0.0,
    "leds.count": 1,
    "leds.positions_mm": [[0.0, 20.0, 10.0]],
    "leds.directions": [[0.0, -0.3, 1.0]],
}


@pytest.mark.filterwarnings("ignore::eyelume.compile.LedAimWarning")
@pytest.mark.filterwarnings("ignore::eyelume.analysis.regions.RegionWarning")
def test_plane_mirror_images_an_led_at_its_mirror_symmetric_point():
    """An LED at z ≈ 10 mm aimed away from the eye at a plane mirror (R = 1) in z = 30 mm:
    the eye-plane irradiance per bin is the closed form of the LED's mirror image (emission
    point (x, y, 60 − z), axis (aₓ, a_y, −a_z)) plus its own direct tail, within the
    multinomial noise (Bonferroni over the bins, family-wise false alarm 1e-3). Without the
    mirror nearly nothing reaches the plane."""
    # centred where the image's rays toward the eye plane cross z = 30 (y 6 … 18, |x| < 8),
    # clear of the camera's axis (x = y = 0), which it would otherwise fold back into the lens
    mirror = {"kind": "mirror", "position_mm": [0.0, 13.0, 30.0], "semi_diameter_mm": 11.5}
    rays = 1_000_000
    cs = compile_scene(_scene([mirror], **DARK))
    result = eyelume.render(cs, eyelume.RenderOptions(rays=rays, seed=3))
    sc = cs.scene
    src, axis = cs.led.points[0], cs.led.axes[0]
    image_src = np.array([src[0], src[1], 60.0 - src[2]])
    image_axis = np.array([axis[0], axis[1], -axis[2]])
    f = relative_intensity(sc.leds.profile)
    i0 = sc.leds.radiant_intensity_w_sr
    direct = _led_irradiance_flux(src, axis, i0, f, sc.eye_plane)
    flux = _led_irradiance_flux(image_src, image_axis, i0, f, sc.eye_plane) + direct
    assert direct.sum() < 0.01 * flux.sum()  # what reaches the plane is the image's light
    p = flux / cs.emitted_w
    expected = rays * p
    sigma = np.sqrt(rays * p * (1 - p))
    assert np.all(expected > 25)
    z = (result.plane_counts - expected) / sigma
    z_max = stats.norm.isf(1e-3 / 2 / z.size)
    assert np.max(np.abs(z)) < z_max, f"worst bin z = {np.max(np.abs(z)):.2f}"
    chi2 = float(np.sum(z**2))
    assert stats.chi2.sf(chi2, df=z.size) > 1e-3, f"chi2 = {chi2:.1f} for {z.size} bins"
    # the brightest bin is the closed form's
    assert np.argmax(result.plane_counts) == np.argmax(flux)


@pytest.mark.filterwarnings("ignore::eyelume.compile.LedAimWarning")
@pytest.mark.filterwarnings("ignore::eyelume.analysis.regions.RegionWarning")
def test_forward_ledger_is_exact_and_a_mirror_files_what_it_absorbs():
    """A mirror R = 0.6, T = 0.1 (A = 0.3) square to the LED's axis, d mm from its emission
    point: every ray within atan(sd/d) of the axis meets it first, P(hit) = 1 − cos^{m+1}(α)
    for the cosᵐ profile, and 0.3 of those are absorbed there. What it reflects returns to the
    LED's body, what it transmits leaves; the dark eye sends nothing back. So its ledger entry
    counts Binomial(N, 0.3 P(hit)) rays; every ray is in exactly one entry."""
    from eyelume.scene.sources import cos_power_exponent

    rays = 400_000
    led_y, led_z, d, sd = 40.0, 10.0, 20.0, 25.0  # the mirror clear of the camera's axis
    overrides = DARK | {
        "leds.directions": [[0.0, 0.0, 1.0]],
        "leds.positions_mm": [[0, led_y, led_z]],
    }
    rb = 2.5  # the default body: 5 mm across
    mirror = {
        "kind": "mirror",
        "name": "absorber",
        "position_mm": [0.0, led_y, led_z + rb + d],
        "semi_diameter_mm": sd,
        "front": {"coating": {"model": "fixed", "reflectance": 0.6, "transmittance": 0.1}},
    }
    cs = compile_scene(_scene([mirror], **overrides))
    fc = trace_forward(cs, rays, seed=5)
    counts = dict(zip(cs.tallies, fc.tallies.tolist(), strict=True))
    assert sum(counts.values()) == rays
    m = cos_power_exponent(cs.scene.leds.profile.half_intensity_angle_deg)
    p_hit = 1.0 - math.cos(math.atan(sd / d)) ** (m + 1)
    p = 0.3 * p_hit
    got = counts["element 0 (absorber)"]
    z = (got - rays * p) / math.sqrt(rays * p * (1 - p))
    assert abs(z) < 4.0, f"absorbed {got}, expected {rays * p:.0f} (z = {z:.2f})"


def test_layout_draws_a_plate_as_a_closed_outline_in_both_views():
    cs = compile_scene(_scene([PLATE]))
    for view in ("yz", "xz"):
        curves = [c for c in system_sections(cs, view=view) if c.category == "element"]
        names = sorted({c.name for c in curves})
        assert names == [
            "element 0 (window) back",
            "element 0 (window) edge",
            "element 0 (window) front",
        ]
        # four pieces: two faces and the edge cut twice; their ends meet pairwise (closed)
        ends = np.array([[c.z[i], c.y[i]] for c in curves for i in (0, -1)])
        assert len(ends) == 8
        for e in ends:
            others = np.linalg.norm(ends - e, axis=1)
            assert np.sort(others)[1] < 0.05, f"{view}: an open end at {e}"


def test_scene_without_elements_compiles_as_before():
    cs = compile_scene(eyelume.load_scene("paper2005"))
    assert not any(n.startswith("element") for n in cs.surface_names + cs.tallies)


CURVED_MIRROR = {
    "kind": "mirror",
    "name": "concave",
    "position_mm": [0.0, 13.0, 30.0],
    "semi_diameter_mm": 11.5,
    "front": {"radius_mm": 60.0},
}
CONVERGING = {
    "kind": "lens",
    "name": "eyepiece",
    "position_mm": [0.0, 0.0, 20.0],
    "thickness_mm": 4.0,
    "glass": "N-BK7",
    "semi_diameter_mm": 15.0,
    "front": {"radius_mm": 60.0},
    "back": {"radius_mm": -60.0},
}


@pytest.mark.parametrize(
    ("element", "says"),
    [(CURVED_MIRROR, "elements.0 (concave) is a curved mirror"),
     (CONVERGING, "elements.0 (eyepiece) is a converging lens that takes")],
)  # fmt: skip
def test_fast_estimator_refuses_what_it_does_not_connect(element, says):
    """The fast estimator connects LEDs by Newton's method through plates, diverging lenses
    and plane mirrors (tests/estimators/test_element_nee.py, test_elements_agreement.py); a
    curved mirror or a converging lens that takes more than 10⁻³ of some LED's flux first
    (here 30 % and 24 % of paper2005's ring LEDs') is refused in one line naming it and the
    share (an eyepiece beside the LEDs is not: tests/estimators/test_integrated_agreement.py)."""
    shares = element_light_shares(compile_scene(_scene([element])))
    assert shares.max() > 0.2
    with pytest.raises(SceneError, match=re.escape(says)):
        eyelume.render(_scene([element]), eyelume.RenderOptions(estimator="fast"))


@pytest.mark.parametrize(
    ("element", "says"),
    [
        (PLATE | {"glass": "BK7"}, "elements.0.glass' = 'BK7'"),
        (PLATE | {"position_mm": [0.0, 0.0, -1.0]}, "reaches into the eye"),
        (PLATE | {"position_mm": [0.0, 30.0, 65.0], "semi_diameter_mm": 5.0}, "LED 1's body"),
        (
            PLATE
            | {
                "front": {"coating": {"model": "fixed", "reflectance": 0.7, "transmittance": 0.4}}
            },  # fmt: skip
            "reflectance + transmittance = 1.1 exceeds 1",
        ),
        (PLATE | {"thickness_mm": float("nan")}, "elements.0.thickness_mm"),
        (PLATE | {"front": {"radius_mm": 50.0}}, "a plate's surfaces are planes"),
        (PLATE | {"position_mm": [0.0, 0.0, 100.0], "semi_diameter_mm": 5.0}, "cuts the camera"),
        (
            {"kind": "mirror", "position_mm": [0, 0, 30], "semi_diameter_mm": 5, "glass": "N-BK7"},
            "a mirror has no glass",
        ),  # fmt: skip
        (
            PLATE
            | {
                "kind": "lens",
                "front": {"radius_mm": 20.0},
                "back": {"radius_mm": -20.0},
                "thickness_mm": 1.0,
            },
            "the surfaces cross before the clear aperture",
        ),  # fmt: skip
    ],
)
def test_bad_element_is_one_line_exit_2(tmp_path, element, says):
    path = _scene_file(tmp_path, [element])
    res = runner.invoke(app, ["info", "--scene", str(path), "--json"])
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and says in lines[0], res.stderr


def test_two_elements_that_intersect_are_refused(tmp_path):
    tilted = {
        "kind": "mirror",
        "position_mm": [0.0, 0.0, 21.0],
        "direction": [0.0, 1.0, 1.0],
        "semi_diameter_mm": 10.0,
    }
    path = _scene_file(tmp_path, [PLATE, tilted])
    res = runner.invoke(app, ["info", "--scene", str(path), "--json"])
    assert res.exit_code == 2
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "elements.1 (mirror) intersects elements.0 (window)" in lines[0]
    # moved clear of the plate, the same mirror is fine
    ok = tilted | {"position_mm": [0.0, 20.0, 40.0]}  # beside the camera's line of sight
    res = runner.invoke(app, ["info", "--scene", str(_scene_file(tmp_path, [PLATE, ok]))])
    assert res.exit_code == 0, res.output


def _scene_file(tmp_path, elements) -> str:
    """paper2005 written out with ``elements`` as [[elements]] tables (TOML written by hand so
    that a NaN or a bad value reaches the loader as a user's file would carry it)."""
    import tomli_w

    base = tmp_path / "base.toml"
    eyelume.save_scene(eyelume.load_scene("paper2005"), base)
    text = base.read_text(encoding="utf-8").replace("elements = []\n", "")
    text += "\n" + tomli_w.dumps({"elements": elements})
    path = tmp_path / "scene.toml"
    path.write_text(text, encoding="utf-8")
    return str(path)


@pytest.mark.parametrize(
    ("rows", "says"),
    [
        ("0,0.01\n95,0.2\n", "angle of incidence 95 deg out of range"),
        ("-5,0.01\n90,0.2\n", "angle of incidence -5 deg out of range"),
        ("0,0.01\n60,0.2\n", "must increase from 0 to 90 deg"),
    ],
)
def test_a_table_with_angles_out_of_range_is_one_line_exit_2(tmp_path, rows, says):
    """Issue 14's bad input: a coating's R(θ) table whose angles leave 0 … 90° (or do not span
    them), through the command line: one line naming the table's field, exit code 2."""
    table = tmp_path / "r.csv"
    table.write_text("angle_deg,R\n" + rows, encoding="utf-8")
    coat = {"model": "table", "table_csv": str(table), "source": "test data"}
    path = _scene_file(tmp_path, [PLATE | {"front": {"coating": coat}}])
    res = runner.invoke(app, ["info", "--scene", path, "--json"])
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and says in lines[0], res.stderr
    assert "elements.0.front.coating.table_csv" in lines[0], lines[0]


def test_reflectance_table_is_checked_and_interpolated_in_the_angle_of_incidence(tmp_path):
    """A coating's R(θ) table: refused with one line when its angles leave 0 … 90 or do not
    span them; compiled, the interface's R at any angle of incidence, from either side, is the
    table's linear interpolation in θ (np.interp), T = 1 − R, nothing absorbed."""
    table = tmp_path / "r.csv"
    coat = {"model": "table", "table_csv": str(table), "source": "test data"}
    el = PLATE | {"front": {"coating": coat}}
    table.write_text("angle_deg,R\n0,0.01\n95,0.2\n", encoding="utf-8")
    with pytest.raises(InputFileError, match=r"angle of incidence 95 deg out of range"):
        compile_scene(_scene([el]))
    table.write_text("angle_deg,R\n0,0.01\n60,0.2\n", encoding="utf-8")
    with pytest.raises(InputFileError, match=r"must increase from 0 to 90 deg"):
        compile_scene(_scene([el]))
    with pytest.raises(SceneError, match="needs source"):
        _scene([PLATE | {"front": {"coating": coat | {"source": ""}}}])
    angles = np.array([0.0, 20.0, 45.0, 60.0, 75.0, 90.0])
    r = np.array([0.01, 0.012, 0.03, 0.08, 0.3, 1.0])
    table.write_text("".join(f"{a},{v}\n" for a, v in zip(angles, r, strict=True)), "utf-8")
    cs = compile_scene(_scene([el]))
    front, back, _ = _rows(cs)
    for theta in (0.0, 10.0, 20.0, 33.3, 59.9, 74.0, 89.5, 90.0):
        for sign in (-1.0, 1.0):
            f = interface_at(cs.sf, cs.si, front, sign * math.cos(math.radians(theta)))
            assert f.reflectance == pytest.approx(np.interp(theta, angles, r), abs=1e-12)
            assert f.absorptance == 0.0
    n = _n_bk7()  # the back surface keeps its Fresnel reflectance
    assert interface_at(cs.sf, cs.si, back, -1.0).reflectance == pytest.approx(
        ((n - 1) / (n + 1)) ** 2, rel=1e-12
    )


@pytest.mark.filterwarnings("ignore::eyelume.compile.LedAimWarning")
@pytest.mark.filterwarnings("ignore::eyelume.analysis.regions.RegionWarning")
def test_mirror_with_a_reflectance_table_weights_the_image_by_r_at_the_angle_of_incidence(
    tmp_path,
):
    """The plane mirror of the image test with a measured-like R(θ) (T = 1 − R): a ray from the
    mirrored emission point to a point of the eye plane meets the mirror (parallel to the plane)
    at the angle β it meets the plane, so each bin's closed form is
    ∫ I₀ f(α) R(β) cos β / r² dA; the forward counts agree bin by bin (Bonferroni, 1e-3)."""
    angles = np.array([0.0, 15.0, 30.0, 45.0, 60.0, 90.0])
    r = np.array([0.9, 0.85, 0.6, 0.3, 0.15, 0.1])
    table = tmp_path / "hot_mirror.csv"
    table.write_text(
        "# angle_deg, R\n" + "".join(f"{a},{v}\n" for a, v in zip(angles, r, strict=True)),
        encoding="utf-8",
    )
    coat = {"model": "table", "table_csv": str(table), "source": "made up for the test"}
    mirror = {
        "kind": "mirror",
        "position_mm": [0.0, 13.0, 30.0],
        "semi_diameter_mm": 11.5,
        "front": {"coating": coat},
    }
    rays = 1_000_000
    cs = compile_scene(_scene([mirror], **DARK))
    result = eyelume.render(cs, eyelume.RenderOptions(rays=rays, seed=11))
    sc = cs.scene
    src, axis = cs.led.points[0], cs.led.axes[0]
    image_src = np.array([src[0], src[1], 60.0 - src[2]])
    image_axis = np.array([axis[0], axis[1], -axis[2]])
    f = relative_intensity(sc.leds.profile)
    i0 = sc.leds.radiant_intensity_w_sr

    def r_of_cos(cos_b):
        return np.interp(np.degrees(np.arccos(np.clip(cos_b, -1, 1))), angles, r)

    flux = _led_irradiance_flux(image_src, image_axis, i0, f, sc.eye_plane, weight=r_of_cos)
    flux += _led_irradiance_flux(src, axis, i0, f, sc.eye_plane)
    p = flux / cs.emitted_w
    expected = rays * p
    sigma = np.sqrt(rays * p * (1 - p))
    assert np.all(expected > 25)
    z = (result.plane_counts - expected) / sigma
    z_max = stats.norm.isf(1e-3 / 2 / z.size)
    assert np.max(np.abs(z)) < z_max, f"worst bin z = {np.max(np.abs(z)):.2f}"
    chi2 = float(np.sum(z**2))
    assert stats.chi2.sf(chi2, df=z.size) > 1e-3, f"chi2 = {chi2:.1f} for {z.size} bins"


def test_the_readme_elements_example_compiles():
    """The README's [[elements]] example, added to paper2005, is a valid scene."""
    import re
    import tomllib
    from pathlib import Path

    readme = (Path(__file__).parents[1] / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```toml\n(.*?)```", readme, flags=re.S)
    # the first block that defines elements (another block may name [[elements]] in a comment)
    elements = next(d["elements"] for d in map(tomllib.loads, blocks) if "elements" in d)
    cs = compile_scene(_scene(elements))
    assert [t for t in cs.tallies if t.startswith("element")] == [
        "element 0 (window)",
        "element 1 (mirror)",
    ]


def test_truth_sees_the_pupil_through_a_tilted_plate_displaced_as_snell_says():
    """A 3 mm N-BK7 plate tilted 30° about x between the eye and the paper's on-axis camera:
    the line of sight along the axis leaves it displaced sideways (by t sin(θ − θ′)/cos θ′, the
    test above), so the camera sees the pupil's centre where, without the plate, an eye moved
    by that displacement would show it. The truth follows its chief rays through the plate and
    agrees within 0.02 px (the chief ray's slope, d/70 mm, changes the displacement only at
    second order); the glints stay visible through the plate."""
    from eyelume.analysis.truth import eye_truth

    th = math.radians(30.0)
    plate = PLATE | {"direction": [0.0, math.sin(th), math.cos(th)]}
    cs = compile_scene(_scene([plate]))
    x, y, z, dx, dy, dz = _through(cs, 0.0, 0.0, 5.0, 0.0, 0.0, 1.0)
    assert (dx, dy, dz) == pytest.approx((0.0, 0.0, 1.0), abs=1e-12)
    n = _n_bk7()
    th_t = math.asin(math.sin(th) / n)
    assert abs(y) == pytest.approx(3.0 * math.sin(th - th_t) / math.cos(th_t), rel=1e-9)
    truth = eye_truth(cs)
    moved = eye_truth(compile_scene(eyelume.load_scene("paper2005", {"head_offset_mm": [0, y, 0]})))
    plain = eye_truth(compile_scene(eyelume.load_scene("paper2005")))
    got, want = truth["pupil"]["centre_px"], moved["pupil"]["centre_px"]
    assert np.hypot(*(np.array(got) - want)) < 0.02, (got, want)
    assert np.hypot(*(np.array(got) - plain["pupil"]["centre_px"])) > 1.0  # the shift is real
    assert truth["glints_visible"] == plain["glints_visible"] == 4


def _follow(cs, p, d, events: int = 8):
    """A ray through the compiled table's element surfaces, taking the stronger branch at each
    (refracted when T ≥ R, else reflected), until it meets no element: (point, direction)."""
    p, d = np.asarray(p, dtype=float), np.asarray(d, dtype=float)
    for _ in range(events):
        s, t = G.nearest_hit(cs.sf, cs.si, *p, *d)
        if s < 0 or not cs.surface_names[s].startswith("element "):
            return p, d
        p = p + t * d
        n = np.array(G.surface_normal(cs.sf, cs.si, s, *p))
        f = interface_at(cs.sf, cs.si, s, float(d @ n))
        ok, *dt = refract(*d, *n, f.n1 / f.n2)
        if ok and 1.0 - f.reflectance - f.absorptance >= f.reflectance:
            d = np.array(dt)
        else:
            d = d - 2.0 * (d @ n) * n
    raise AssertionError("the ray did not leave the elements")


def test_a_thick_lens_element_focuses_a_paraxial_ray_at_its_back_focal_distance():
    """A biconvex N-BK7 element R₁ = +30, R₂ = −30 mm, t = 4 mm: Φ = (n − 1)(1/R₁ − 1/R₂ +
    (n − 1) t / (n R₁ R₂)), back focal distance BFD = (1 − (n − 1) t / (n R₁)) / Φ. A ray
    parallel to the axis at h = 0.01 mm crosses the axis BFD behind the back vertex (to
    O(h²), 1e-6 relative)."""
    r1, r2, t = 30.0, -30.0, 4.0
    lens = {
        "kind": "lens",
        "position_mm": [0.0, 0.0, 20.0],
        "thickness_mm": t,
        "glass": "N-BK7",
        "semi_diameter_mm": 10.0,
        "front": {"radius_mm": r1},
        "back": {"radius_mm": r2},
    }
    cs = compile_scene(_scene([lens]))
    n = _n_bk7()
    power = (n - 1) * (1 / r1 - 1 / r2 + (n - 1) * t / (n * r1 * r2))
    bfd = (1 - (n - 1) * t / (n * r1)) / power
    h = 0.01
    p, d = _follow(cs, [0.0, h, 5.0], [0.0, 0.0, 1.0])
    z_cross = p[2] - p[1] * d[2] / d[1]
    assert z_cross - (20.0 + t) == pytest.approx(bfd, rel=1e-6)


@pytest.mark.parametrize("h", [1.0, 5.0, 9.5])
def test_a_parabolic_mirror_element_sends_every_axial_ray_through_its_focus(h):
    """A concave paraboloid (k = −1, R = −40 mm: centre of curvature toward the light) reflects
    every ray parallel to its axis through the focus R/2 = 20 mm in front of its vertex,
    whatever the height (exactly: no spherical aberration)."""
    mirror = {
        "kind": "mirror",
        "position_mm": [0.0, 0.0, 45.0],
        "semi_diameter_mm": 10.0,
        "front": {"radius_mm": -40.0, "conic": -1.0},
    }
    # vr-offaxis: its camera looks at the eye from the side, so the mirror is out of its view
    cs = compile_scene(eyelume.load_scene("vr-offaxis", {"elements": [mirror]}))
    f = cs.frame  # its tables are in the camera's frame: in and out through the world's
    p, d = _follow(cs, f.point([0.0, h, 30.0]), f.vector([0.0, 0.0, 1.0]))
    p, d = f.world_point(p), f.world_vector(d)
    assert d[2] < 0  # folded back toward the eye
    t = -p[1] / d[1]
    np.testing.assert_allclose(p + t * d, [0.0, 0.0, 25.0], atol=1e-9)


def test_a_left_eye_mirrors_the_elements_like_the_rest_of_the_file():
    """A left eye's scene is the file mirrored x → −x: an element at x = +6 mm, axis tilted
    toward +x, sits at x = −6 mm, tilted toward −x (the paper's on-axis camera: camera frame =
    world)."""
    el = PLATE | {
        "position_mm": [6.0, 0.0, 20.0],
        "direction": [0.3, 0.0, 1.0],
        "semi_diameter_mm": 5.0,
    }
    for which, sign in (("right", 1.0), ("left", -1.0)):
        cs = compile_scene(_scene([el], **{"eye_pose.which": f'"{which}"'}))
        front = _rows(cs)[0]
        assert cs.sf[front, G.OX] == pytest.approx(sign * 6.0)
        axis = cs.sf[front, G.R20 : G.R22 + 1]
        np.testing.assert_allclose(axis, np.array([sign * 0.3, 0.0, 1.0]) / math.hypot(0.3, 1.0))


def test_info_lists_each_element_with_its_paraxial_power():
    """`eyelume info`'s elements: a lens's EFL by the thick-lens formula, its back focal
    distance where a traced paraxial ray crosses the axis, a plate's Fresnel R at normal
    incidence; a concave mirror's focal length −R/2."""
    from eyelume.info import scene_info

    lens = {
        "kind": "lens",
        "name": "eyepiece",
        "position_mm": [0.0, 0.0, 20.0],
        "thickness_mm": 4.0,
        "glass": "N-BK7",
        "semi_diameter_mm": 10.0,
        "front": {"radius_mm": 30.0},
        "back": {"radius_mm": -30.0},
    }
    mirror = {
        "kind": "mirror",
        "position_mm": [0.0, 22.0, 45.0],  # beside the camera's line of sight
        "semi_diameter_mm": 8.0,
        "front": {"radius_mm": -40.0},
    }
    scene = _scene([lens, mirror])
    info = scene_info(scene)["elements"]
    n = _n_bk7()
    power = (n - 1) * (1 / 30 + 1 / 30 - (n - 1) * 4 / (n * 900))
    assert info[0]["efl_mm"] == pytest.approx(1 / power, rel=1e-12)
    assert info[0]["index"] == pytest.approx(n, rel=1e-15)
    assert info[0]["surfaces"][0]["reflectance_normal"] == pytest.approx(((n - 1) / (n + 1)) ** 2)
    cs = compile_scene(eyelume.load_scene("paper2005", {"elements": [lens]}))
    p, d = _follow(cs, [0.0, 0.01, 5.0], [0.0, 0.0, 1.0])
    assert p[2] - p[1] * d[2] / d[1] - 24.0 == pytest.approx(
        info[0]["back_focal_distance_mm"], rel=1e-6
    )
    assert info[1]["focal_length_mm"] == 20.0 and info[1]["ledger_entry"] == "element 1 (mirror)"


def test_cli_render_with_the_fast_estimator_refuses_a_curved_mirror_in_one_line(tmp_path):
    path = _scene_file(tmp_path, [CURVED_MIRROR])
    res = runner.invoke(app, ["render", "--scene", path, "--out", str(tmp_path / "out")])
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and "is a curved mirror" in lines[0], res.stderr
    assert not (tmp_path / "out").exists()  # refused before anything is made or run


#: vr-offaxis's camera moved below the eye, looking up (+y) at a 45° fold mirror in front of
#: the eye that turns its view onto the eye (the paper's Fig. 1 layout, in miniature): 30 mm up
#: to the mirror, 33 mm on to the corneal vertex, focused at 63 mm.
FOLDED = {
    "camera.position_mm": [0.0, -30.0, 33.0],
    "camera.look_at_mm": [0.0, 0.0, 33.0],
    "camera.ideal.focus_distance_mm": 63.0,
}
FOLD = {
    "kind": "mirror",
    "name": "fold",
    "position_mm": [0.0, 0.0, 33.0],
    "direction": [0.0, -1.0, -1.0],
    "semi_diameter_mm": 12.0,
}


def test_a_fold_mirror_turns_the_cameras_view_onto_the_eye():
    """Without the mirror the camera (looking along +y) sees no eye and is refused; with the
    45° mirror its line of sight is folded onto the eye: it compiles, and the truth finds the
    pupil's centre at the picture's centre (the folded axis meets the eye's axis) and every
    glint."""
    from eyelume.analysis.truth import eye_truth

    with pytest.raises(SceneError, match="sees no eye"):
        compile_scene(eyelume.load_scene("vr-offaxis", FOLDED))
    cs = compile_scene(eyelume.load_scene("vr-offaxis", FOLDED | {"elements": [FOLD]}))
    truth = eye_truth(cs)
    cols, rows = cs.picture.cols, cs.picture.rows
    np.testing.assert_allclose(
        truth["pupil"]["centre_px"], [(cols - 1) / 2, (rows - 1) / 2], atol=1e-3
    )
    assert truth["glints_visible"] == len(cs.led.points)


def test_a_mirror_that_sends_the_view_nowhere_is_one_line_exit_2(tmp_path):
    """The same mirror turned the other way folds the view away from the eye (+z)."""
    sets = [
        "camera.position_mm=[0, -30, 33]",
        "camera.look_at_mm=[0, 0, 33]",
        "camera.ideal.focus_distance_mm=63",
        'elements=[{kind="mirror", name="fold", position_mm=[0, 0, 33], direction=[0, -1, 1], '
        "semi_diameter_mm=12}]",
    ]
    args = ["info", "--scene", "vr-offaxis"] + [x for v in sets for x in ("--set", v)]
    res = runner.invoke(app, args)
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, res.stderr
    assert "sees no eye: its line of sight, through element 0 (fold), ends on nothing" in lines[0]


def test_a_hot_mirror_reflects_above_its_cutoff_and_each_wavelength_group_sees_its_own():
    """A hot mirror (cut-off 900 nm: R 0.95, T 0.03 above; R 0.02, T 0.98 below): LEDs at 850
    and 940 nm render as two wavelength groups, each compiled with the mirror's R and
    A = 1 − R − T at its own wavelength."""
    from eyelume.compile import wavelength_groups

    coat = {
        "model": "fixed",
        "reflectance": 0.95,
        "transmittance": 0.03,
        "cutoff_nm": 900.0,
        "reflectance_below": 0.02,
        "transmittance_below": 0.98,
    }
    mirror = {
        "kind": "mirror",
        "name": "hot",
        "position_mm": [0.0, 22.0, 45.0],
        "semi_diameter_mm": 8.0,
        "front": {"coating": coat},
    }
    scene = _scene([mirror], **{"leds.wavelength_nm": [850.0, 940.0, 850.0, 940.0]})
    nominal = compile_scene(scene)
    got = {}
    for g in wavelength_groups(scene):
        cg = compile_scene(scene, g, nominal=nominal)
        s = _rows(cg)[0]
        got[g.wavelength_nm] = (cg.sf[s, G.REFL], cg.sf[s, G.ABSORB])
    assert got[850.0] == pytest.approx((0.02, 0.0))
    assert got[940.0] == pytest.approx((0.95, 0.02))
    with pytest.raises(SceneError, match="need cutoff_nm"):
        _scene([mirror | {"front": {"coating": coat | {"cutoff_nm": None}}}])
    with pytest.raises(SceneError, match="needs reflectance_below"):
        _scene([mirror | {"front": {"coating": coat | {"reflectance_below": None}}}])


def test_regions_follow_a_mirror_fold():
    """The regions' map takes an element's stronger branch (a window's refraction, a mirror's
    fold), as the truth does: behind the 45° fold mirror the pupil mask is the pupil the truth
    finds through it (its centroid within a pixel of the truth's pupil centre, its area that
    of the truth's pupil ellipse within 15 %), and no warning; a hot mirror that turns the
    view at one LED wavelength and not at another is warned about in one line."""
    import warnings

    from eyelume.analysis.regions import RegionWarning, region_masks
    from eyelume.analysis.truth import eye_truth

    cs = compile_scene(eyelume.load_scene("vr-offaxis", FOLDED | {"elements": [FOLD]}))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RegionWarning)
        region_masks(compile_scene(_scene([PLATE])))
        masks = region_masks(cs, reflections=False)
    truth = eye_truth(cs)["pupil"]
    rows, cols = np.nonzero(masks["pupil"])
    assert masks["skin"].sum() > 0 and masks["iris"].sum() > 0
    assert math.hypot(cols.mean() - truth["centre_px"][0], rows.mean() - truth["centre_px"][1]) < 1
    x, y = np.array(truth["edge_px"]).T  # the pupil's outline, in order: the shoelace area
    area = 0.5 * abs(np.dot(x, np.roll(y, 1)) - np.dot(y, np.roll(x, 1)))
    assert rows.size == pytest.approx(area, rel=0.15)
    hot = FOLD | {
        "front": {
            "coating": {
                "model": "fixed",
                "reflectance": 0.92,
                "transmittance": 0.08,
                "cutoff_nm": 720.0,
                "reflectance_below": 0.10,
                "transmittance_below": 0.88,
            }
        }
    }
    two = {"elements": [hot], "leds.wavelength_nm": [850.0, 650.0] * 4}
    cs = compile_scene(eyelume.load_scene("vr-offaxis", FOLDED | two))
    with pytest.warns(RegionWarning, match=r"elements.0 is a mirror .*R = 0.92.*R = 0.1"):
        region_masks(cs, reflections=False)


def _cli_lines(args):
    res = runner.invoke(app, args)
    return res, [ln for ln in res.stderr.splitlines() if ln.strip()]


_INTEGRATED_INFO = ["info", "--scene", "paper2005-integrated", "--json"]


def test_a_beamsplitter_turned_to_send_the_view_nowhere_is_still_refused():
    """Both branches of a 50/50 beamsplitter are followed now (a fold with R ≤ T compiles,
    tests/test_integrated_preset.py); turned so that its reflection goes away from the eye
    (+z) and its transmission past it (−x), neither reaches the eye: one line naming the
    path, exit 2."""
    sets = [
        "elements.1.front.coating.reflectance=0.5",
        "elements.1.front.coating.transmittance=0.5",
        "elements.1.direction=[0.70710678, 0, 0.70710678]",
    ]
    res, lines = _cli_lines(_INTEGRATED_INFO + [x for v in sets for x in ("--set", v)])
    assert res.exit_code == 2, res.output
    assert len(lines) == 1, res.stderr
    assert (
        "sees no eye: its line of sight, through element 1 (hot mirror), ends on nothing"
        in (lines[0])
    )


def test_a_hot_mirror_whose_cutoff_is_above_the_wavelength_is_named_as_the_cause():
    """A hot mirror with its cut-off at 900 nm, above the LEDs' 850 nm, reflects only its
    below-cut-off R: at R = 0.10 the camera still sees the eye by the fold, dimly, and a
    warning names the cut-off; at R = 0 it sees none, and the one-line refusal names the
    cut-off as the cause (it said only "ends on nothing" before)."""
    cut = ["--set", "elements.1.front.coating.cutoff_nm=900"]
    res, lines = _cli_lines(_INTEGRATED_INFO + cut)
    assert res.exit_code == 0, res.output
    warned = [ln for ln in lines if "cut-off" in ln]
    assert len(warned) == 1, res.stderr
    assert "element 1 (hot mirror) front reflects R = 0.1 at 850 nm" in warned[0]
    assert "its cut-off 900 nm, elements.1.front.coating.cutoff_nm, is above" in warned[0]
    res, lines = _cli_lines(
        _INTEGRATED_INFO + cut + ["--set", "elements.1.front.coating.reflectance_below=0"]
    )
    assert res.exit_code == 2, res.output
    assert len(lines) == 1, res.stderr
    assert "sees no eye" in lines[0] and "reflects R = 0 at 850 nm" in lines[0], lines[0]
    assert (
        "cut-off 900 nm, elements.1.front.coating.cutoff_nm, is above the wavelength" in (lines[0])
    )


@pytest.mark.parametrize(
    ("second", "says"),
    [
        ({"name": "window"}, "elements.1.name = 'window', as elements.0's"),
        ({"name": ""}, "elements.1.name = '' (unnamed), as elements.0, both a plate"),
    ],
)
def test_two_elements_of_one_name_are_refused(tmp_path, second, says):
    """truth.json's ghost chains name an element's surfaces by its name (its kind when
    unnamed): two plates both called "window" (or both unnamed) made them ambiguous and were
    accepted. One line naming the second element's name, exit 2; renamed, they compile."""
    first = PLATE | ({"name": ""} if not second["name"] else {})
    other = PLATE | {"position_mm": [0.0, 0.0, 40.0], "semi_diameter_mm": 10.0} | second
    res, lines = _cli_lines(["info", "--scene", _scene_file(tmp_path, [first, other]), "--json"])
    assert res.exit_code == 2, res.output
    assert len(lines) == 1 and says in lines[0], res.stderr
    other |= {"name": "second window"}
    res, _ = _cli_lines(["info", "--scene", _scene_file(tmp_path, [first, other]), "--json"])
    assert res.exit_code == 0, res.output


def test_an_element_behind_the_eye_plane_inside_the_head_is_refused(tmp_path):
    """A small plate 40 mm behind the corneal vertex, inside the skull where no tissue is
    modelled (it touches neither the eyeball nor a face solid), was accepted. Like an LED
    (``leds: … crosses the eye plane``), an element must lie in front of the eye plane: one
    line naming elements.0.position_mm and its value, exit 2."""
    inside = PLATE | {"position_mm": [0.0, 0.0, -40.0], "semi_diameter_mm": 5.0}
    res, lines = _cli_lines(["info", "--scene", _scene_file(tmp_path, [inside]), "--json"])
    assert res.exit_code == 2, res.output
    assert len(lines) == 1, res.stderr
    assert "elements.0.position_mm = [0.0, 0.0, -40.0]" in lines[0], lines[0]
    assert "behind the eye plane z = 0 mm" in lines[0], lines[0]
