"""Derived first-order optics of a scene (``eyelume info``): lens, eye, glasses, LEDs, optical
elements."""

from __future__ import annotations

import math

import numpy as np

from eyelume.compile import (
    CompiledScene,
    WavelengthGroup,
    camera_pose,
    compile_scene,
    element_label,
    element_pose,
    eye_direction,
    eye_paraxial,
    eye_point,
    lens_indices,
    lens_paraxial,
    real_best_focus,
    single_wavelength,
    wavelength_groups,
)
from eyelume.kernels import geometry as G
from eyelume.kernels import sequential as Q
from eyelume.scene.eye import LAMBDA_D, anterior_quadric, eye_indices, glint_reflectance
from eyelume.scene.focus import focus
from eyelume.scene.model import Element, LedProfile, Scene
from eyelume.scene.optics import ParaxialSystem, curvature
from eyelume.scene.pose import opencv_extrinsics
from eyelume.scene.sources import cos_power_exponent, led_poses

__all__ = ["camera_info", "info_text", "scene_info"]


def camera_info(cs: CompiledScene) -> dict:
    """The camera's pose and its pinhole model in OpenCV's convention.

    ``K`` (3 × 3, pixels): fx = fy = f_p / p with p the picture's pixel pitch on the sensor and
    f_p the pinhole distance — for an ideal lens the image distance v (the model is exact up to
    the distortion ``dist``), for a prescription |m| times the entrance pupil's distance from
    the object plane (paraxial); cx, cy the picture's centre, pixel centres at integers.
    ``R``, ``t``: a world point p (mm) has OpenCV camera coordinates R p + t, origin at the
    entrance pupil (:func:`eyelume.scene.pose.opencv_extrinsics`). ``position_mm`` and
    ``view_direction`` (a unit vector, whether the file gives a direction or a look-at point)
    are in the world frame, a left eye's mirrored."""
    scene, fo = cs.scene, cs.first_order
    width, _ = scene.sensor.field_mm
    pitch = width / scene.sensor.cols
    pinhole = abs(fo.magnification) * fo.entrance_pupil_z
    r, t = opencv_extrinsics(cs.frame, fo.entrance_pupil_z)
    pos, view, roll = camera_pose(scene)  # world: a left eye's mirrored
    ideal = scene.camera.ideal if scene.camera.optics == "ideal" else None
    return {
        "optics": scene.camera.optics,
        "position_mm": pos.tolist(),
        "view_direction": (view / np.linalg.norm(view)).tolist(),
        "roll_deg": roll,
        "object_distance_mm": fo.object_distance,
        "opencv": {
            "K": [
                [pinhole / pitch, 0.0, (scene.sensor.cols - 1) / 2],
                [0.0, pinhole / pitch, (scene.sensor.rows - 1) / 2],
                [0.0, 0.0, 1.0],
            ],
            "dist": [ideal.k1, ideal.k2, 0.0, 0.0] if ideal else [0.0, 0.0, 0.0, 0.0],
            "R": r.tolist(),
            "t_mm": t.tolist(),
            "image_size": [scene.sensor.cols, scene.sensor.rows],
        },
    }


def _ideal_lens_info(cs: CompiledScene) -> dict:
    ideal = cs.scene.camera.ideal
    assert ideal is not None
    fo = cs.first_order
    half = [
        math.degrees(math.atan(w / 2 / ideal.image_distance_mm)) for w in cs.scene.sensor.field_mm
    ]
    return {
        "name": "ideal thin lens",
        "effective_focal_length_mm": ideal.efl_mm,
        "f_number_efl_over_epd": ideal.f_number,
        "entrance_pupil_diameter_mm": 2 * ideal.pupil_radius_mm,
        "object_distance_mm": fo.object_distance,
        "image_distance_mm": ideal.image_distance_mm,
        "magnification": fo.magnification,
        "working_f_number": fo.working_f_number,
        "field_of_view_deg": [2 * h for h in half],
        "distortion_k1_k2": [ideal.k1, ideal.k2],
        "image_plane_z_mm": cs.image_z,
    }


def scene_info(scene: Scene) -> dict:
    """First-order properties of the scene at its wavelength, as JSON-ready data (mm, D, W)."""
    cs = compile_scene(scene)
    out = {
        "scene": scene.name,
        "wavelength_nm": scene.wavelength_nm,
        "camera": camera_info(cs),
    }
    if scene.camera.optics == "ideal":
        out["imaging_lens"] = _ideal_lens_info(cs)
        out["glasses"] = {}
    else:
        out["imaging_lens"], out["glasses"] = _prescription_info(scene, cs)
    out["eye"] = _eye_info(scene)
    out["leds"] = _led_info(scene, cs)
    if scene.elements:
        out["elements"] = [_element_info(cs, k, el) for k, el in enumerate(scene.elements)]
    if not single_wavelength(scene):
        out["wavelength_groups"] = [_group_info(scene, cs, g) for g in wavelength_groups(scene)]
    if scene.camera.optics == "prescription":
        out["reading_of_the_paper"] = (
            "The F-number is read as EFL / entrance-pupil diameter at infinite conjugate (the "
            "paper's F/2.51); the stop is sized for it. The working F-number above is that of "
            "the finite eye-plane conjugate."
        )
    return out


def _group_info(scene: Scene, nominal: CompiledScene, group: WavelengthGroup) -> dict:
    """One wavelength group as rendered (:func:`eyelume.compile.compile_scene` with the group):
    its LEDs and power, the camera's first-order figures and the eye's indices at its
    wavelength, and for a prescription each glass's index there and whether the wavelength lies
    in the glass's catalog range (beyond it, the compile warns)."""
    cg = compile_scene(scene, group, nominal=nominal)
    fo = cg.first_order
    out = {
        "wavelength_nm": group.wavelength_nm,
        "leds": list(group.leds),
        "power_w": cg.emitted_w,
        "effective_focal_length_mm": fo.efl,
        "entrance_pupil_diameter_mm": 2.0 * fo.entrance_pupil_radius,
        "magnification": fo.magnification,
        "eye_indices": eye_indices(scene.eye, group.wavelength_nm),
    }
    if scene.camera.optics == "prescription":
        _, used = lens_indices(cg.scene)
        out["glasses"] = {
            s.glass: {
                "index": cg.lens_indices[j + 1],
                "wavelength_in_catalog_range": used[s.glass].in_range(group.wavelength_nm),
            }
            for j, s in enumerate(scene.lens.surfaces)  # type: ignore[union-attr]
            if s.glass in used
        }
    return out


def _prescription_info(scene: Scene, cs: CompiledScene) -> tuple[dict, dict]:
    lens = scene.lens
    assert lens is not None
    par = lens_paraxial(scene, cs.lens_indices)
    s_obj = lens.object_distance_mm
    stop_sd = float(cs.lf[cs.stop_index, Q.L_SD])
    best = real_best_focus(cs.lf)
    foc = focus(scene, par, cs.stop_index, stop_sd, None if best is None else best[0])
    _, used = lens_indices(scene)
    glasses = {}
    for j, s in enumerate(lens.surfaces):
        if s.glass in used and s.glass not in glasses:
            g = used[s.glass]
            glasses[s.glass] = {
                "paper_name": s.paper_glass or s.glass,
                "index": cs.lens_indices[j + 1],
                "nd_catalog": g.nd,
                "vd_catalog": g.vd,
                "nd_from_formula": g.index(LAMBDA_D),
                "wavelength_in_catalog_range": g.in_range(scene.wavelength_nm),
                "source": g.source,
            }
    return {
        "name": lens.name,
        "effective_focal_length_mm": par.efl,
        "back_focal_distance_mm": par.back_focal_distance,
        "f_number_efl_over_epd": lens.f_number,
        "entrance_pupil_diameter_mm": par.efl / lens.f_number,
        "stop_semi_diameter_mm": stop_sd,
        "object_distance_mm": s_obj,
        "paraxial_image_distance_mm": par.image_distance(s_obj),
        "prescription_image_distance_mm": lens.surfaces[-1].thickness_mm,
        "eye_plane_magnification": par.magnification(s_obj),
        "working_f_number": par.working_f_number(s_obj, cs.stop_index, stop_sd),
        "semi_diameters_mm": [float(v) for v in cs.lf[:, Q.L_SD]],
        "image_plane_z_mm": cs.image_z,
        "best_focus_distance_mm": foc.best_focus_mm,
        "axial_rms_spot_radius_at_best_focus_mm": None if best is None else best[1],
        "sensor_defocus_mm": foc.defocus_mm,
        "depth_of_focus_mm": foc.depth_of_focus_mm,
    }, glasses


def _cornea_info(scene: Scene) -> dict:
    """The anterior cornea's two meridians (radius mm, asphericity Q), its keratometric
    cylinder (D, 337.5/R_steep − 337.5/R_flat), the flat meridian's TABO axis of the physical
    eye (a left eye's is 180° − the file's) and its decentration and tilt as written
    (``eye.cornea``, :class:`~eyelume.scene.model.AnteriorCornea`)."""
    eye = scene.eye
    c1, c2, k = anterior_quadric(eye)
    axis = eye.cornea.axis_deg
    if scene.eye_pose.which == "left":
        axis = (180.0 - axis) % 180.0
    return {
        "radius_flat_mm": 1.0 / c1,
        "radius_steep_mm": 1.0 / c2,
        "q_flat": k,
        "q_steep": (1.0 + k) * c1 / c2 - 1.0,
        "cylinder_d": 337.5 * (c2 - c1),
        "axis_deg_tabo": axis,
        "decentration_mm": list(eye.cornea.decentration_mm),
        "tilt_deg": list(eye.cornea.tilt_deg),
    }


def _eye_info(scene: Scene) -> dict:
    eye_wl = eye_paraxial(scene)
    eye_d = eye_paraxial(scene, LAMBDA_D)
    return {
        "model": scene.eye.model,
        "dispersion": scene.eye.dispersion,
        "glint_reflectance": (
            "fresnel"
            if scene.eye.cornea_reflection == "fresnel"
            else glint_reflectance(scene.eye, scene.wavelength_nm)
        ),
        "which": scene.eye_pose.which,
        # world mm: the eye's pose with the head offset, gaze turned (a left eye mirrored)
        "corneal_vertex_mm": eye_point(scene, [0.0, 0.0, 0.0]).tolist(),
        "rotation_centre_mm": eye_point(scene, [0.0, 0.0, -scene.eye.rotation_centre_mm]).tolist(),
        "optical_axis": eye_direction(scene, [0.0, 0.0, 1.0]).tolist(),
        "anterior_cornea": _cornea_info(scene),
        "power_d": eye_wl.power * 1000.0,
        "power_d_at_587nm": eye_d.power * 1000.0,
        "indices": dict(
            zip(
                ["air"] + [f"after {s.name}" for s in scene.eye.surfaces[:-1]],
                eye_indices(scene.eye, scene.wavelength_nm),
                strict=True,
            )
        ),
    }


def _profile_info(profile: LedProfile) -> dict:
    if profile.kind == "cos_power":
        return {
            "kind": "cos_power",
            "half_intensity_angle_deg": profile.half_intensity_angle_deg,
            "cos_power_exponent": cos_power_exponent(profile.half_intensity_angle_deg),
            "spread_full_angle_deg": 2 * profile.half_intensity_angle_deg,
        }
    return {"kind": "table", "table_csv": profile.table_csv}


def _led_info(scene: Scene, cs: CompiledScene) -> dict:
    """Every LED's place (world mm), I₀, profile, wavelength, body and emitter diameters and
    power; the ring's figures only
    for a ring (LEDs placed one by one have none)."""
    led = scene.leds
    centres, axes = led_poses(led)
    out: dict = {
        "count": led.count,
        "placement": "ring" if led.positions_mm is None else "one by one (positions_mm)",
        "total_power_w": cs.emitted_w,
    }
    if led.positions_mm is None:
        out["ring"] = {
            "height_mm": led.height_mm,
            "distance_mm": led.distance_mm,
            "azimuths_deg": led.azimuths(),
            "ring_axis": list(led.ring_axis),
            "ring_centre_mm": list(led.ring_centre_mm),
            **(
                {"pitch_deg": led.pitch_deg}
                if led.aim_at_mm is None
                else {"aim_at_mm": list(led.aim_at_mm)}
            ),
        }
    out["per_led"] = [
        {
            "position_mm": centres[k].tolist(),
            "axis": axes[k].tolist(),
            "radiant_intensity_w_sr": i0,
            "profile": _profile_info(profile),
            "wavelength_nm": lam,
            "body_shape": shape,
            "body_diameter_mm": 2 * body,
            "body_length_mm": length,
            "emission_point_mm": (centres[k] + offset * axes[k]).tolist(),
            "emitter_diameter_mm": emitter,
            "effective_solid_angle_sr": float(cs.omega_eff[k]),
            "power_w": float(cs.led_powers_w[k]),
        }
        for k, (i0, profile, lam, body, shape, length, offset, emitter) in enumerate(
            zip(
                led.intensities_w_sr(),
                led.profiles(),
                led.wavelengths_nm(scene.wavelength_nm),
                led.body_radii_mm(),
                led.body_shapes(),
                led.body_lengths_mm(),
                led.emission_offsets_mm(),
                led.emitter_diameters_mm(),
                strict=True,
            )
        )
    ]
    return out


def _element_info(cs: CompiledScene, k: int, el: Element) -> dict:
    """Optical element ``k`` as compiled: its first vertex and unit axis in the world frame
    (mm), its glass's index at the scene's wavelength, each surface's coating and its
    reflectance at normal incidence (Fresnel: ((n − 1)/(n + 1))²), and its paraxial power: a
    lens's or plate's EFL and back focal distance (thick lens, in air), a mirror's focal length
    −R/2 (positive for a concave mirror facing the incoming light, i.e. R < 0)."""
    origin, rot = element_pose(cs.scene, el)
    label = element_label(k, el)
    rows = [s for s, name in enumerate(cs.surface_names) if name.startswith(label + " ")]
    n = float(cs.sf[rows[0], G.N_B])
    surfaces = []
    for surf in el.surfaces:
        c = surf.coating
        assert c is not None  # Element.surfaces fills every coating in
        if c.model == "fresnel":
            r0 = ((n - 1.0) / (n + 1.0)) ** 2
        elif c.model == "fixed":
            r0 = c.fixed_at(cs.scene.wavelength_nm)[0]
        else:
            r0 = None
        entry = {"radius_mm": surf.radius_mm, "conic": surf.conic, "coating": c.model}
        entry["reflectance_normal"] = r0
        if c.model == "table":
            entry["table_csv"], entry["source"] = c.table_csv, c.source
        surfaces.append(entry)
    out = {
        "name": el.name,
        "kind": el.kind,
        "ledger_entry": label,
        "vertex_mm": [float(x) for x in origin],
        "axis": [float(x) for x in rot[2]],
        "semi_diameter_mm": el.semi_diameter_mm,
        "surfaces": surfaces,
    }
    if el.kind == "mirror":
        r = el.front.radius_mm
        out["focal_length_mm"] = None if math.isinf(r) else -r / 2.0
        return out
    par = ParaxialSystem(
        tuple(curvature(s.radius_mm) for s in el.surfaces), (float(el.thickness_mm),), (1.0, n, 1.0)
    )
    power = par.power
    out["glass"] = el.glass
    out["index"] = n
    out["thickness_mm"] = el.thickness_mm
    out["edge_thickness_mm"] = el.edge_thickness_mm
    if power == 0.0:
        out["efl_mm"] = out["back_focal_distance_mm"] = None
    else:
        ys, us = par.trace(1.0, 0.0)
        out["efl_mm"] = 1.0 / power
        out["back_focal_distance_mm"] = -ys[-1] / us[-1]
    return out


def _scalar(v) -> str:
    if isinstance(v, bool) or v is None:
        return {True: "true", False: "false", None: "none"}[v]
    return f"{v:.6g}" if isinstance(v, float) else str(v)


def _flat(v) -> bool:
    return isinstance(v, list) and all(not isinstance(x, dict | list) for x in v)


def info_text(data: dict) -> str:
    """:func:`scene_info`'s dictionary as text to read (``eyelume info`` without ``--json``):
    one ``name: value`` line per entry, a nested table indented under its name, a list of
    numbers on one line, numbers to 6 significant digits (``--json`` keeps full precision).

    >>> print(info_text({"lens": {"efl_mm": 12.3456789, "sd_mm": [1.0, 2.5]}, "ok": True}))
    lens:
      efl_mm: 12.3457
      sd_mm: 1, 2.5
    ok: true
    """
    lines: list[str] = []

    def walk(d: dict, depth: int) -> None:
        pad = "  " * depth
        for key, v in d.items():
            if isinstance(v, dict):
                lines.append(f"{pad}{key}:")
                walk(v, depth + 1)
            elif _flat(v):
                lines.append(f"{pad}{key}: {', '.join(_scalar(x) for x in v)}")
            elif isinstance(v, list) and all(_flat(x) for x in v):  # a matrix: one row a line
                lines.append(f"{pad}{key}:")
                lines.extend([f"{pad}  {', '.join(_scalar(x) for x in row)}" for row in v])
            elif isinstance(v, list):
                lines.append(f"{pad}{key}:")
                for k, item in enumerate(v):
                    if isinstance(item, dict):
                        lines.append(f"{pad}  [{k}]")
                        walk(item, depth + 2)
                    else:
                        lines.append(f"{pad}  [{k}] {_scalar(item)}")
            else:
                lines.append(f"{pad}{key}: {_scalar(v)}")

    walk(data, 0)
    return "\n".join(lines)
