"""Derived first-order optics of a scene (``eyelume info``): lens, eye, glasses, LEDs."""

from __future__ import annotations

from eyelume.compile import compile_scene, eye_paraxial, lens_indices, lens_paraxial
from eyelume.kernels import sequential as Q
from eyelume.scene.eye import LAMBDA_D, eye_indices
from eyelume.scene.focus import focus
from eyelume.scene.model import Scene
from eyelume.scene.sources import cos_power_exponent

__all__ = ["scene_info"]


def scene_info(scene: Scene) -> dict:
    """First-order properties of the scene at its wavelength, as JSON-ready data (mm, D, W)."""
    cs = compile_scene(scene)
    lens = scene.lens
    par = lens_paraxial(scene, cs.lens_indices)
    s_obj = lens.object_distance_mm
    stop_sd = float(cs.lf[cs.stop_index, Q.L_SD])
    foc = focus(scene, par, cs.stop_index, stop_sd)
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
    eye_wl = eye_paraxial(scene)
    eye_d = eye_paraxial(scene, LAMBDA_D)
    led = scene.leds
    return {
        "scene": scene.name,
        "wavelength_nm": scene.wavelength_nm,
        "imaging_lens": {
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
            "sensor_defocus_mm": foc.defocus_mm,
            "depth_of_focus_mm": foc.depth_of_focus_mm,
        },
        "eye": {
            "model": scene.eye.model,
            "power_d": eye_wl.power * 1000.0,
            "power_d_at_587nm": eye_d.power * 1000.0,
            "indices": dict(
                zip(
                    ["air"] + [f"after {s.name}" for s in scene.eye.surfaces[:-1]],
                    eye_indices(scene.eye, scene.wavelength_nm),
                    strict=True,
                )
            ),
        },
        "glasses": glasses,
        "leds": {
            "count": led.count,
            "cos_power_exponent": (
                cos_power_exponent(led.profile.half_intensity_angle_deg)
                if led.profile.kind == "cos_power"
                else None
            ),
            "power_per_led_w": cs.led_power_w,
            "total_power_w": cs.emitted_w,
            "effective_solid_angle_sr": cs.omega_eff,
            "pitch_deg": led.pitch_deg,
            "height_mm": led.height_mm,
            "distance_mm": led.distance_mm,
            "spread_full_angle_deg": 2 * led.profile.half_intensity_angle_deg
            if led.profile.kind == "cos_power"
            else None,
        },
        "reading_of_the_paper": (
            "F/2.51 is read as EFL / entrance-pupil diameter at infinite conjugate; the stop is "
            "sized for it. The working F-number above is that of the finite eye-plane conjugate."
        ),
    }
