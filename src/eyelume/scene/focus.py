"""Does the imaging lens form a real image of the eye plane, near the sensor? (issue 12)

First-order (paraxial) optics of the lens prescription (:class:`~eyelume.scene.optics.
ParaxialSystem`, object space air): the eye plane, ``lens.object_distance_mm`` before the first
vertex, is imaged at s′ after the last vertex, s′ = −y_k / u′_k for the paraxial ray from its
axial point. The sensor is at the last surface's ``thickness_mm``, t.

* s′ ≤ 0 or infinite: the eye plane has a **virtual image** (or none) — no picture of the eye
  can form on any sensor, whatever the renderer draws — so the scene is refused
  (:class:`~eyelume.errors.GeometryError`).
* |t − s_b| > N_w · p: the sensor lies outside the **depth of focus**, and a
  :class:`FocusWarning` says by how much. s_b is the **best focus** found with real rays — the
  plane of least RMS spot radius of a fan from the eye plane's axial point traced through the
  prescription (:func:`eyelume.compile.real_best_focus`; the paraxial s′ only when no real-ray
  focus is given), because spherical aberration moves the best focus away from s′. N_w =
  1 / (2 n′ |u′|) is the paraxial working F-number of the eye-plane conjugate and p the sampling
  pixel on the image plane (the larger of ``sensor.width_mm / cols`` and
  ``sensor.height_mm / rows``): a point defocused by Δz blurs into a disc of diameter Δz / N_w,
  so within ± N_w · p the blur stays within one pixel.

  The paper's lens at 850 nm: s′ = 199.45 mm, but the marginal rays focus 1.05 mm closer
  (undercorrected spherical aberration) and the real best focus is s_b = 198.52 mm, where the
  axial RMS spot radius is 0.017 mm; the sensor, t = 200.46 mm, is 1.94 mm behind it (RMS spot
  radius 0.174 mm there). N_w = 4.00: inside ± 2.11 mm at the paper's 87 × 65 pixels of
  0.529 mm, outside ± 0.29 mm at 640 × 480 — there the picture is blurred over about five
  pixels, and the warning says so (move the sensor to ≈ 198.5 mm).
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
    best_focus_mm: float | None = None  # s_b, last vertex → real-ray best focus (None: not traced)

    @property
    def focus_mm(self) -> float:
        """The focus the sensor is judged against: s_b when traced, else s′."""
        return self.image_distance_mm if self.best_focus_mm is None else self.best_focus_mm

    @property
    def defocus_mm(self) -> float:
        """t − s_b (t − s′ without a real-ray focus): the sensor's distance from focus (+:
        behind it)."""
        return self.sensor_distance_mm - self.focus_mm


def focus(
    scene: Scene,
    par: ParaxialSystem,
    stop: int,
    stop_semi_diameter: float,
    best_focus_mm: float | None = None,
) -> Focus:
    """The eye plane's image against the sensor (no check; see :func:`check_focus`).

    Parameters
    ----------
    scene : Scene
    par : ParaxialSystem
        The imaging lens at the scene's wavelength (``compile.lens_paraxial``).
    stop, stop_semi_diameter : int, float
        The aperture stop's surface index and its semi-diameter (mm).
    best_focus_mm : float, optional
        The real-ray best focus s_b (mm after the last vertex,
        :func:`eyelume.compile.real_best_focus`); without it the sensor is judged against the
        paraxial image.
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
        best_focus_mm=None if best_focus_mm is None else float(best_focus_mm),
    )


def check_focus(
    scene: Scene,
    par: ParaxialSystem,
    stop: int,
    stop_semi_diameter: float,
    best_focus_mm: float | None = None,
    warn: bool = True,
) -> Focus:
    """:func:`focus`, refusing a virtual image and (with ``warn``) warning when the sensor is
    out of focus — judged against the real-ray best focus ``best_focus_mm`` when given. The
    warning names ``scene.wavelength_nm``: each wavelength group of LEDs is compiled at its own
    (:func:`eyelume.compile.compile_scene`), and each focuses on its own.

    Raises
    ------
    GeometryError
        The eye plane has no real image (one line naming ``lens`` and the image distance).

    Warns
    -----
    FocusWarning
        |t − s_b| > N_w · p (module docstring).
    """
    f = focus(scene, par, stop, stop_semi_diameter, best_focus_mm)
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
    if warn and abs(f.defocus_mm) > f.depth_of_focus_mm:
        what = "paraxial image" if f.best_focus_mm is None else "real-ray best focus"
        warnings.warn(
            f"lens: at {scene.wavelength_nm:g} nm the sensor "
            f"(lens.surfaces.{len(scene.lens.surfaces) - 1}.thickness_mm = "
            f"{f.sensor_distance_mm:g}) is {abs(f.defocus_mm):.3g} mm "
            f"{'behind' if f.defocus_mm > 0 else 'in front of'} the eye plane's {what} "
            f"({f.focus_mm:.5g} mm), outside the depth of focus ± N_w·p = "
            f"± {f.working_f_number:.3g} × {f.pixel_mm:.3g} mm = ± {f.depth_of_focus_mm:.3g} mm: "
            "the picture is blurred over several pixels",
            FocusWarning,
            stacklevel=3,
        )
    return f
