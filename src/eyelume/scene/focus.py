"""Does the imaging lens form a real image of the eye plane, near the sensor? (issue 12)

First-order (paraxial) optics of the lens prescription (:class:`~eyelume.scene.optics.
ParaxialSystem`, object space air): the eye plane, ``lens.object_distance_mm`` before the first
vertex, is imaged at s′ after the last vertex, s′ = −y_k / u′_k for the paraxial ray from its
axial point. The sensor is at the last surface's ``thickness_mm``, t.

* s′ ≤ 0 or infinite: the eye plane has a **virtual image** (or none) — no picture of the eye
  can form on any sensor, whatever the renderer draws — so the scene is refused
  (:class:`~eyelume.errors.GeometryError`).
* |t − s′| > N_w · p: the sensor lies outside the **depth of focus**, and a
  :class:`FocusWarning` says by how much. N_w = 1 / (2 n′ |u′|) is the paraxial working
  F-number of the eye-plane conjugate and p the sampling pixel on the image plane (the larger
  of ``sensor.width_mm / cols`` and ``sensor.height_mm / rows``): a point defocused by Δz blurs
  into a disc of diameter Δz / N_w, so within ± N_w · p the blur stays within one pixel. The
  paper's lens at 850 nm: s′ = 199.45 mm, t = 200.46 mm, N_w = 4.00, p = 0.529 mm, so the
  sensor is 1.01 mm from focus, inside ± 2.11 mm.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

from eyelume.errors import EyelumeWarning, GeometryError
from eyelume.scene.model import Scene
from eyelume.scene.optics import ParaxialSystem

__all__ = ["Focus", "FocusWarning", "check_focus", "focus"]


class FocusWarning(EyelumeWarning):
    """The sensor lies outside the depth of focus of the eye plane's paraxial image."""


@dataclass(frozen=True)
class Focus:
    """The eye plane's paraxial image and the sensor (mm; see the module docstring)."""

    image_distance_mm: float  # s′, last vertex → paraxial image (≤ 0: virtual)
    sensor_distance_mm: float  # t, last vertex → sensor
    working_f_number: float  # N_w of the eye-plane conjugate
    pixel_mm: float  # p, the sampling pixel on the image plane
    depth_of_focus_mm: float  # N_w · p: the half-width of the depth of focus

    @property
    def defocus_mm(self) -> float:
        """t − s′: the sensor's distance from the paraxial image (+: behind it)."""
        return self.sensor_distance_mm - self.image_distance_mm


def focus(scene: Scene, par: ParaxialSystem, stop: int, stop_semi_diameter: float) -> Focus:
    """The eye plane's paraxial image against the sensor (no check; see :func:`check_focus`).

    Parameters
    ----------
    scene : Scene
    par : ParaxialSystem
        The imaging lens at the scene's wavelength (``compile.lens_paraxial``).
    stop, stop_semi_diameter : int, float
        The aperture stop's surface index and its semi-diameter (mm).
    """
    s_obj = scene.lens.object_distance_mm
    _, us = par.trace(s_obj * 1e-3, 1e-3)
    u_k = float(us[-1])
    image = par.image_distance(s_obj) if u_k != 0.0 else math.inf
    n_w = par.working_f_number(s_obj, stop, stop_semi_diameter) if u_k != 0.0 else math.inf
    sensor = scene.sensor
    width, height = sensor.field_mm
    pixel = max(width / sensor.cols, height / sensor.rows)
    return Focus(
        image_distance_mm=float(image),
        sensor_distance_mm=scene.lens.surfaces[-1].thickness_mm,
        working_f_number=float(n_w),
        pixel_mm=pixel,
        depth_of_focus_mm=float(n_w) * pixel,
    )


def check_focus(scene: Scene, par: ParaxialSystem, stop: int, stop_semi_diameter: float) -> Focus:
    """:func:`focus`, refusing a virtual image and warning when the sensor is out of focus.

    Raises
    ------
    GeometryError
        The eye plane has no real image (one line naming ``lens`` and the image distance).

    Warns
    -----
    FocusWarning
        |t − s′| > N_w · p (module docstring).
    """
    f = focus(scene, par, stop, stop_semi_diameter)
    s_obj = scene.lens.object_distance_mm
    if not (math.isfinite(f.image_distance_mm) and f.image_distance_mm > 0.0):
        where = (
            "at infinity"
            if not math.isfinite(f.image_distance_mm)
            else f"{-f.image_distance_mm:.4g} mm before the last surface"
        )
        raise GeometryError(
            f"the eye plane ({s_obj:g} mm before the lens) has no real image: its paraxial "
            f"image is virtual, {where}, so no picture of the eye forms on the sensor "
            f"(EFL {par.efl:.4g} mm)",
            field="lens",
        )
    if abs(f.defocus_mm) > f.depth_of_focus_mm:
        warnings.warn(
            f"lens: the sensor (lens.surfaces.{len(scene.lens.surfaces) - 1}.thickness_mm = "
            f"{f.sensor_distance_mm:g}) is {abs(f.defocus_mm):.3g} mm "
            f"{'behind' if f.defocus_mm > 0 else 'in front of'} the eye plane's paraxial image "
            f"({f.image_distance_mm:.5g} mm), outside the depth of focus ± N_w·p = "
            f"± {f.working_f_number:.3g} × {f.pixel_mm:.3g} mm = ± {f.depth_of_focus_mm:.3g} mm: "
            "the picture is blurred over several pixels",
            FocusWarning,
            stacklevel=3,
        )
    return f
