"""The closed-form eye-plane irradiance (the generator's LED–eye plane system) against independent
references: a brute-force midpoint sum, the forward Monte Carlo tally, and energy conservation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import integrate, stats

import eyelume
from eyelume.compile import compile_scene
from eyelume.estimators.closed_form import (
    auto_order,
    bin_irradiance,
    configuration_irradiance,
    eye_plane_irradiance,
    geometry_problem,
    led_emitters,
    plane_edges,
    product_grid,
    sweep_irradiance,
)
from eyelume.scene.eye import limbus_geometry
from eyelume.scene.optics import curvature, sag
from eyelume.scene.sources import cos_power_exponent, led_poses, relative_intensity

PAPER_GRID = (range(20, 41, 5), range(20, 71, 5), range(0, 31, 5))
MC_RAYS = 6_000_000


def _rel_change(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b) / np.abs(b)))


def test_emitters_are_the_tracers_emission_points(paper_scene):
    sc = paper_scene
    emit, axes = led_emitters(
        sc.leds, [sc.leds.height_mm], [sc.leds.distance_mm], [sc.leds.pitch_deg]
    )
    centres, ax = led_poses(sc.leds)
    np.testing.assert_allclose(axes[0], ax, atol=1e-15)
    np.testing.assert_allclose(emit[0], centres + ax * sc.leds.body_diameter_mm / 2, atol=1e-12)


def test_single_led_on_axis_bins_match_a_brute_force_midpoint_sum(paper_scene):
    """One LED on the axis pointing straight down: E = I₀ cosᵐα cos β / r², cos α = cos β = h/r."""
    z = 30.0
    scene = eyelume.apply_overrides(
        paper_scene,
        {
            "leds.count": 1,
            "leds.azimuths_deg": [0.0],
            "leds.height_mm": 0.0,
            "leds.distance_mm": z,
            "leds.pitch_deg": 0.0,
        },
    )
    e = eye_plane_irradiance(scene)
    i0 = scene.leds.radiant_intensity_w_sr
    m = cos_power_exponent(scene.leds.profile.half_intensity_angle_deg)
    h = z - scene.leds.body_diameter_mm / 2  # emission point: the apex of the body
    xe, ye = plane_edges(scene.eye_plane)
    n = 400  # sub-cells per bin side: midpoint error ~ (bin/n)² f''/24 ≈ 1e-8 relative
    for row, col in [(7, 10), (0, 0), (14, 20), (3, 15), (7, 0)]:
        u = (np.arange(n) + 0.5) / n
        xs = xe[col] + (xe[col + 1] - xe[col]) * u
        ys = ye[row] + (ye[row + 1] - ye[row]) * u
        x, y = np.meshgrid(xs, ys)
        r2 = x * x + y * y + h * h
        brute = np.mean(i0 * (h * h / r2) ** (m / 2) * h / r2**1.5)
        assert e[row, col] == pytest.approx(brute, rel=1e-6), (row, col)


@pytest.mark.slow
def test_doubling_the_order_changes_no_bin_by_more_than_1e6(paper_scene):
    """Every configuration of the paper's grid; and a narrow (5° half-angle) LED, which needs a
    higher order, on the grid's nearest, middle and farthest distances."""
    narrow = eyelume.apply_overrides(paper_scene, {"leds.profile.half_intensity_angle_deg": 5.0})
    for scene, grid in (
        (paper_scene, PAPER_GRID),
        (narrow, (PAPER_GRID[0], [20, 45, 70], PAPER_GRID[2])),
    ):
        y, z, t = product_grid(*grid)
        emit, axes = led_emitters(scene.leds, y, z, t)
        xe, ye = plane_edges(scene.eye_plane)
        n = auto_order(xe, ye, emit, axes, scene.leds.profile)
        chosen = sweep_irradiance(scene, *grid)
        np.testing.assert_array_equal(chosen, sweep_irradiance(scene, *grid, order=n))
        doubled = sweep_irradiance(scene, *grid, order=2 * n)
        assert _rel_change(chosen, doubled) <= 1e-6, (scene.leds.profile, n)
    assert n > 4  # the narrow beam did need more points than the paper's LED


def test_sweep_is_c_ordered_and_matches_single_configurations(paper_scene):
    heights, distances, pitches = [20, 35], [25, 60], [0, 10, 30]
    sweep = sweep_irradiance(paper_scene, heights, distances, pitches)
    assert sweep.shape == (12, 15, 21)
    k = 0
    for y in heights:
        for z in distances:
            for t in pitches:
                single = eye_plane_irradiance(
                    paper_scene, height_mm=y, distance_mm=z, pitch_deg=t, order=4
                )
                np.testing.assert_allclose(sweep[k], single, rtol=1e-9)
                k += 1
    # defaults come from the scene; a compiled scene is accepted too
    sc = paper_scene.leds
    np.testing.assert_array_equal(
        eye_plane_irradiance(paper_scene),
        eye_plane_irradiance(paper_scene, sc.height_mm, sc.distance_mm, sc.pitch_deg),
    )


def test_impossible_geometry_is_rejected(paper_scene):
    with pytest.raises(ValueError, match="crosses the eye plane"):
        eye_plane_irradiance(paper_scene, distance_mm=2.5)
    with pytest.raises(ValueError, match="configuration 1 .*overlap"):
        configuration_irradiance(paper_scene, [30, 1], [50, 50], [0, 0])
    assert geometry_problem(paper_scene.leds, 30, 2.6, 0) is None
    assert "negative" in geometry_problem(paper_scene.leds, -1, 50, 0)


def test_eye_lies_behind_the_eye_plane(paper_scene):
    """Nothing of the eye rises above z = 0 (world), so with the face off the forward tally of the
    eye plane is the LEDs' direct light in every bin: no bin needs excluding below."""
    eye = paper_scene.eye
    depth = 0.0  # z' (into the eye) of each surface's vertex
    for s in eye.surfaces:
        r = np.linspace(0.0, s.semi_diameter_mm, 201)
        zprime = depth + sag(curvature(s.radius_mm), s.conic, r)
        assert np.all(zprime >= -1e-12), s.name
        depth += s.thickness_mm
    r_l, z_l, z_c = limbus_geometry(eye)
    assert z_l > 0  # the sclera starts behind the limbus, itself behind the vertex plane
    assert eye.surfaces[0].radius_mm > 0  # the cornea bulges toward +z: touches z = 0 only at r=0


def test_closed_form_matches_the_forward_monte_carlo_tally():
    """paper2005, face off: per-bin z-scores of the forward counts against RAYS·Φ_bin/Φ_emitted."""
    scene = eyelume.load_scene("paper2005", {"face.enabled": False})
    cs = compile_scene(scene)
    result = eyelume.render(cs, eyelume.RenderOptions(rays=MC_RAYS, seed=11))
    area = (scene.eye_plane.width_mm / scene.eye_plane.cols) * (
        scene.eye_plane.height_mm / scene.eye_plane.rows
    )
    p = eye_plane_irradiance(scene) * area / cs.emitted_w  # probability a ray lands in each bin
    expected = MC_RAYS * p
    assert np.all(expected > 100)
    sigma = np.sqrt(MC_RAYS * p * (1 - p))
    z = (result.plane_counts - expected) / sigma
    z_max = stats.norm.isf(1e-3 / 2 / z.size)  # Bonferroni: family-wise false alarm 1e-3
    assert np.max(np.abs(z)) < z_max, f"worst bin z = {np.max(np.abs(z)):.2f} (limit {z_max:.2f})"
    chi2 = float(np.sum(z**2))
    assert stats.chi2.sf(chi2, df=z.size) > 1e-3, f"chi2 = {chi2:.1f} for {z.size} bins"
    # and the total: all bins together, within 4 standard errors
    total, total_exp = result.plane_counts.sum(), expected.sum()
    assert abs(total - total_exp) < 4 * math.sqrt(total_exp)


def _geometric_edges(core: float, core_bins: int, growth: float, reach: float) -> np.ndarray:
    """Symmetric edges: uniform bins over |x| < core, then bins growing by ``growth`` to reach."""
    pos = list(np.linspace(0.0, core, core_bins + 1))
    while pos[-1] < reach:
        pos.append(pos[-1] * growth)
    pos = np.asarray(pos)
    return np.concatenate([-pos[:0:-1], pos])


@pytest.mark.parametrize("pitch_deg", [0.0, 30.0])
def test_energy_over_a_huge_plane_is_the_power_into_the_lower_hemisphere(paper_scene, pitch_deg):
    """∫∫ E dA over a plane 20 m wide = I₀ ∫ f(α) dΩ over the directions with d_z < 0."""
    leds = paper_scene.leds
    m = cos_power_exponent(leds.profile.half_intensity_angle_deg)
    i0 = leds.radiant_intensity_w_sr
    emit, axes = led_emitters(leds, [30.0], [20.0], [pitch_deg])
    emit, axes = emit[:, :1], axes[:, :1]  # one LED
    edges = _geometric_edges(40.0, 40, 1.15, 10_000.0)
    e = bin_irradiance(edges, edges, emit, axes, i0, leds.profile)[0]
    w = np.diff(edges)
    flux = float(np.sum(e * w[:, None] * w[None, :]))

    # the power into d_z < 0: about the LED axis a = (−sin θ, 0, −cos θ) with u = (cos θ, 0,
    # −sin θ), v = y, a direction at (α, φ) has d_z = −cos α cos θ − sin α cos φ sin θ, so for
    # each φ the LED reaches the plane for α < α_max(φ) and ∫₀^α_max cosᵐα sin α dα is closed form
    th = math.radians(pitch_deg)

    def alpha_max(phi: float) -> float:
        c = math.cos(phi) * math.sin(th)
        return math.pi / 2 if c >= 0 else min(math.pi / 2, math.atan2(math.cos(th), -c))

    def ring(phi: float) -> float:
        return (1 - math.cos(alpha_max(phi)) ** (m + 1)) / (m + 1)

    hemisphere, _ = integrate.quad(ring, 0.0, 2 * math.pi, limit=200, epsabs=0, epsrel=1e-12)
    hemisphere *= i0
    if pitch_deg == 0:
        assert hemisphere == pytest.approx(2 * math.pi * i0 / (m + 1), rel=1e-12)
    # a 20 m plane misses what leaves within ~0.1° of the horizon: nothing of a cos^m beam on
    # its axis, 4.7e-6 of one pitched by 30° (whose far side reaches the horizon at α = 60°)
    assert flux == pytest.approx(hemisphere, rel=1e-9 if pitch_deg == 0 else 2e-5)
    assert flux <= hemisphere * (1 + 1e-9)


def test_tabulated_profile_matches_numpy_reference(tmp_path, paper_scene):
    """A datasheet-like table: the kernel's interpolation is the tracers' (np.interp in α)."""
    csv = tmp_path / "led.csv"
    csv.write_text(
        "angle_deg,relative\n0,1\n10,0.97\n20,0.72\n30,0.38\n40,0.15\n60,0.03\n80,0.01\n",
        encoding="utf-8",
    )
    scene = eyelume.apply_overrides(
        paper_scene, {"leds.profile.kind": "table", "leds.profile.table_csv": str(csv)}
    )
    f = relative_intensity(scene.leds.profile)
    emit, axes = led_emitters(scene.leds, [30.0], [25.0], [20.0])
    xe, ye = plane_edges(scene.eye_plane)
    got = bin_irradiance(xe, ye, emit, axes, 1.0, scene.leds.profile, order=6)[0]
    # the same 6-point rule written with NumPy and the scene's own profile function
    g, gw = np.polynomial.legendre.leggauss(6)
    ref = np.zeros_like(got)
    for row in range(15):
        ys = 0.5 * (ye[row] + ye[row + 1]) + 0.5 * (ye[row + 1] - ye[row]) * g
        for col in range(21):
            xs = 0.5 * (xe[col] + xe[col + 1]) + 0.5 * (xe[col + 1] - xe[col]) * g
            x, y = np.meshgrid(xs, ys)
            for e, a in zip(emit[0], axes[0], strict=True):
                d = np.stack([x - e[0], y - e[1], np.full_like(x, -e[2])])
                r = np.linalg.norm(d, axis=0)
                cos_a = np.einsum("i,ijk->jk", a, d) / r
                val = np.where(cos_a > 0, f(np.arccos(np.clip(cos_a, -1, 1))), 0.0) * e[2] / r**3
                ref[row, col] += np.einsum("i,j,ij->", gw, gw, val) / 4
    np.testing.assert_allclose(got, ref, rtol=1e-12)
