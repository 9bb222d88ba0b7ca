"""The y–z section (plane x = 0) of a compiled scene, as polylines for layout drawings.

Reads the compiled surface tables, so it sits beside :mod:`eyelume.compile`. Curves are cut
where a surface's clip ranges end, so each returned polyline is one connected piece.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from eyelume.compile import CompiledScene
from eyelume.kernels import geometry as G
from eyelume.kernels import sequential as Q
from eyelume.scene.optics import sag

__all__ = ["Section", "system_sections"]


@dataclass(frozen=True)
class Section:
    """A polyline of the system's y–z section (x = 0) for layout drawings (world mm)."""

    name: str
    category: str
    z: np.ndarray
    y: np.ndarray


def _category(name: str, action: int) -> str:
    if name.startswith("LED"):
        return "led"
    if action == G.ACT_LENS:
        return "lens"
    if action == G.ACT_REFRACT or name in ("iris", "iris root", "retina", "sclera"):
        return "eye"
    return "tissue"


def _runs(points: np.ndarray, keep: np.ndarray) -> list[np.ndarray]:
    """Split an ordered point list into the connected runs where ``keep`` holds."""
    out, start = [], None
    for i, k in enumerate(np.append(keep, False)):
        if k and start is None:
            start = i
        elif not k and start is not None:
            if i - start >= 2:
                out.append(points[start:i])
            start = None
    return out


def _clip_mask(sf: np.ndarray, s: int, world: np.ndarray) -> np.ndarray:
    rot = sf[s, G.R00 : G.R22 + 1].reshape(3, 3)
    local = (world - sf[s, G.OX : G.OZ + 1]) @ rot.T
    r2 = local[:, 0] ** 2 + local[:, 1] ** 2
    return (
        (r2 >= sf[s, G.RMIN2] - 1e-9)
        & (r2 <= sf[s, G.RMAX2] + 1e-9)
        & (local[:, 2] >= sf[s, G.ZLO] - 1e-9)
        & (local[:, 2] <= sf[s, G.ZHI] + 1e-9)
    )


def _surface_points(sf: np.ndarray, si: np.ndarray, s: int, extent: float) -> np.ndarray:
    """World points of surface ``s`` along its intersection with x = 0 (ordered)."""
    rot = sf[s, G.R00 : G.R22 + 1].reshape(3, 3)
    o = sf[s, G.OX : G.OZ + 1]
    shape = si[s, G.SHAPE]
    if shape == G.SHAPE_CONIC:
        rmax = min(math.sqrt(sf[s, G.RMAX2]), extent)
        c, k = sf[s, G.CURV], sf[s, G.CONIC]
        # the meridian in x = 0: local direction (cos ψ, sin ψ, 0) whose world x part vanishes
        psi = math.atan2(-rot[0, 0], rot[1, 0])
        r = np.linspace(-rmax, rmax, 801)
        z = sag(c, k, np.abs(r))
        local = np.stack([r * math.cos(psi), r * math.sin(psi), z], 1)
        return local @ rot + o
    if shape == G.SHAPE_SPHERE:
        rad = sf[s, G.RADIUS]
        if abs(o[0]) >= rad:
            return np.zeros((0, 3))
        rc = math.sqrt(rad * rad - o[0] ** 2)
        a = np.linspace(0.0, 2 * math.pi, 721)
        return np.stack([np.zeros_like(a), o[1] + rc * np.cos(a), o[2] + rc * np.sin(a)], 1)
    # cylinder: points (R cos a, R sin a, h) local; solve world x = 0 for h (axis not ⟂ x)
    rad = sf[s, G.RADIUS]
    ax = rot[2]
    a = np.linspace(0.0, 2 * math.pi, 721)
    ring = rad * (np.outer(np.cos(a), rot[0]) + np.outer(np.sin(a), rot[1]))
    if abs(ax[0]) > 1e-9:
        h = -(o[0] + ring[:, 0]) / ax[0]
        return o + ring + np.outer(h, ax)
    # axis in the section plane: two lines along the axis where the ring crosses x = 0
    lines = []
    h = np.linspace(sf[s, G.ZLO], sf[s, G.ZHI], 201)
    for ang in np.unique(np.round(np.arctan2(-rot[0, 0], rot[1, 0]) + np.array([0, math.pi]), 12)):
        p = o + rad * (math.cos(ang) * rot[0] + math.sin(ang) * rot[1])
        if abs(p[0]) < 1e-6:
            lines.append(p + np.outer(h, ax))
    return np.concatenate(lines) if lines else np.zeros((0, 3))


def system_sections(cs: CompiledScene, extent: float = 60.0) -> list[Section]:
    """Every surface's y–z section: eye, tissues, LEDs, lens surfaces, stop, sensor, eye plane."""
    out: list[Section] = []
    for s, name in enumerate(cs.surface_names):
        if cs.si[s, G.ACTION] == G.ACT_LENS:
            continue  # drawn with the sequential lens below
        pts = _surface_points(cs.sf, cs.si, s, extent)
        if len(pts) == 0:
            continue
        keep = _clip_mask(cs.sf, s, pts) & (np.abs(pts[:, 1]) <= extent)
        for run in _runs(pts, keep):
            out.append(
                Section(name, _category(name, int(cs.si[s, G.ACTION])), run[:, 2], run[:, 1])
            )
    for j in range(cs.lf.shape[0]):
        sd = cs.lf[j, Q.L_SD]
        c, k = cs.lf[j, Q.L_CURV], cs.lf[j, Q.L_CONIC]
        if j == cs.stop_index:
            for sign in (1.0, -1.0):
                y = sign * np.array([sd, sd + 8.0])
                out.append(Section("aperture stop", "stop", np.full(2, cs.lf[j, Q.L_Z]), y))
            continue
        r = np.linspace(-sd, sd, 201)
        z = cs.lf[j, Q.L_Z] + sag(c, k, np.abs(r))
        out.append(Section(f"lens S{j + 1}", "lens", z, r))
    half = cs.picture.height_mm / 2
    out.append(Section("sensor", "sensor", np.full(2, cs.image_z), np.array([-half, half])))
    half = cs.eye_plane.height_mm / 2
    out.append(Section("eye plane", "receiver", np.zeros(2), np.array([-half, half])))
    return out
