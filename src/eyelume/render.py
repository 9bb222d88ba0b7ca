"""Render a scene with the forward Monte Carlo estimator: eye image, eye-plane irradiance, ledger.

This is the Python API behind ``eyelume render``::

    import eyelume
    scene = eyelume.load_scene("paper2005", {"leds.height_mm": 40})
    result = eyelume.render(scene, rays=2_000_000, seed=1)
    result.eye_image          # (rows, cols) W/mm², row 0 at the top of the picture
    result.ledger             # {"sensor": W, "iris": W, ..., "escaped": W}
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from eyelume.compile import CompiledScene, compile_scene
from eyelume.estimators.forward import trace_forward
from eyelume.scene.model import Scene

__all__ = ["RenderResult", "render"]


@dataclass
class RenderResult:
    """What a render produces.

    Attributes
    ----------
    eye_image : (rows, cols) float64
        Image-plane irradiance (W/mm²) binned over the sensor; row 0 is the top of the picture as
        a person views it (world +y), columns run with world +x as seen from the camera.
    eye_plane : (rows, cols) float64
        Eye-plane irradiance (W/mm²) toward the eye over the receiver; row 0 at +y.
    image_counts, plane_counts : int64 arrays
        Rays behind each bin; a bin's relative standard error is about 1/√count.
    ledger : dict[str, float]
        Where the emitted power ended (W), summing to ``emitted_w``.
    picture_extent_mm, plane_extent_mm : (left, right, bottom, top)
        Millimetre coordinates of the picture (the sensor plane turned by 180°, so x_picture =
        −x_sensor and y_picture = −y_sensor) and of the eye plane (world x, y).
    """

    scene: Scene
    rays: int
    seed: int
    wall_time_s: float
    ray_power_w: float
    emitted_w: float
    eye_image: np.ndarray
    eye_plane: np.ndarray
    image_counts: np.ndarray
    plane_counts: np.ndarray
    ledger: dict[str, float]
    interactions: int
    interrupted: bool
    picture_extent_mm: tuple[float, float, float, float]
    plane_extent_mm: tuple[float, float, float, float]

    def summary(self) -> dict:
        """The run's summary as plain JSON-ready data (``summary.json``)."""
        absorbed = {
            k: v for k, v in self.ledger.items() if k not in ("sensor", "escaped") and v > 0
        }
        return {
            "scene": self.scene.name,
            "estimator": "forward",
            "rays": self.rays,
            "seed": self.seed,
            "interrupted": self.interrupted,
            "wall_time_s": round(self.wall_time_s, 4),
            "surface_interactions": self.interactions,
            "power_w": {
                "emitted": self.emitted_w,
                "sensor": self.ledger["sensor"],
                "absorbed": absorbed,
                "escaped": self.ledger["escaped"],
                "sum": float(sum(self.ledger.values())),
            },
            "units": {"eye_image": "W/mm^2", "eye_plane": "W/mm^2", "power": "W"},
        }


def _extent(width: float, height: float) -> tuple[float, float, float, float]:
    return (-width / 2, width / 2, -height / 2, height / 2)


def render(
    scene: Scene | CompiledScene,
    rays: int | None = None,
    seed: int | None = None,
    batch_size: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> RenderResult:
    """Trace a scene with the plain forward Monte Carlo estimator.

    Parameters
    ----------
    scene
        A :class:`Scene` (compiled here) or an already compiled scene.
    rays, seed, batch_size
        Default to the scene's ``[run]`` table. The result depends on (scene, rays, seed) only.
    progress
        Called as ``progress(rays_done, rays_total)`` after each batch.
    """
    cs = scene if isinstance(scene, CompiledScene) else compile_scene(scene)
    sc = cs.scene
    rays = sc.run.rays if rays is None else int(rays)
    seed = sc.run.seed if seed is None else int(seed)
    t0 = time.perf_counter()
    fc = trace_forward(cs, rays, seed, batch_size, progress)
    wall = time.perf_counter() - t0
    w = cs.emitted_w / fc.rays
    px_area = (sc.sensor.width_mm / sc.sensor.cols) * (sc.sensor.height_mm / sc.sensor.rows)
    pl_area = (sc.eye_plane.width_mm / sc.eye_plane.cols) * (
        sc.eye_plane.height_mm / sc.eye_plane.rows
    )
    return RenderResult(
        scene=sc,
        rays=fc.rays,
        seed=seed,
        wall_time_s=wall,
        ray_power_w=w,
        emitted_w=cs.emitted_w,
        eye_image=fc.image * (w / px_area),
        eye_plane=fc.plane * (w / pl_area),
        image_counts=fc.image,
        plane_counts=fc.plane,
        ledger={name: float(n) * w for name, n in zip(cs.tallies, fc.tallies, strict=True)},
        interactions=fc.interactions,
        interrupted=fc.interrupted,
        picture_extent_mm=_extent(sc.sensor.width_mm, sc.sensor.height_mm),
        plane_extent_mm=_extent(sc.eye_plane.width_mm, sc.eye_plane.height_mm),
    )
