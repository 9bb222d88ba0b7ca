"""Sections of a compiled scene in the world (headset) frame, as polylines for layout drawings.

Two orthogonal views: ``"yz"``, the section by the plane x = x₀ (z across, y up), and ``"xz"``,
the section by y = y₀ (z across, x up), through the eye's nominal corneal vertex (x₀, y₀, z₀)
(its pose, :class:`eyelume.scene.model.EyePose`; 0 for the paper's rig). The eye, the face,
the LED bodies and the optical elements (a lens's or plate's two surfaces and edge: a closed
outline; a mirror's one surface) are cut by the plane; the camera — its lens surfaces, stop
and sensor, drawn in the camera's meridional plane closest to the view — and its field of view
(from the entrance pupil to the edges of the imaged field) are projected onto it, so a camera
anywhere shows where it is and what it sees. LEDs show their axes.

Reads the compiled surface tables (camera frame, :mod:`eyelume.scene.pose`) and turns them to
the world frame, so it sits beside :mod:`eyelume.compile`. Curves are cut where a surface's
clip ranges end, so each returned polyline is one connected piece.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from eyelume.compile import CompiledScene, eye_plane_origin
from eyelume.kernels import geometry as G
from eyelume.kernels import sequential as Q
from eyelume.scene.optics import sag

__all__ = ["Section", "VIEWS", "system_sections", "world_table"]

#: The views: the world axis cut to 0 (the section plane's normal) and the vertical axis.
VIEWS = {"yz": (0, 1), "xz": (1, 0)}


@dataclass(frozen=True)
class Section:
    """A polyline of a view for layout drawings (world mm): ``z`` across and ``y`` the view's
    vertical coordinate (world y in the ``"yz"`` view, world x in the ``"xz"`` view)."""

    name: str
    category: str
    z: np.ndarray
    y: np.ndarray


def _category(name: str, action: int) -> str:
    if name.startswith("element "):  # compile.element_label: an optical element's surfaces
        return "element"
    if name.startswith("LED"):
        return "led"
    if name.startswith("camera body"):
        return "camera"
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


def _lash_points(sf: np.ndarray, s: int, rot: np.ndarray, o: np.ndarray, cut: int) -> np.ndarray:
    """An eyelash fringe's lashes in the plane p[cut] = 0: its cone's meridians there (the
    plane through its axis), within the lashes' span, NaN rows between them."""
    psi = math.atan2(-rot[0, cut], rot[1, cut])
    z = np.linspace(sf[s, G.ZLO], sf[s, G.ZHI], 51)
    half_span = 0.5 * sf[s, G.LASH_COUNT] * sf[s, G.LASH_PITCH]
    lines = []
    for a in (psi, psi + math.pi):
        a = math.remainder(a, 2 * math.pi)
        if abs(a) <= half_span:
            r = sf[s, G.CURV] * z
            local = np.stack([r * math.cos(a), r * math.sin(a), z], 1)
            lines.append(local @ rot + o)
    if not lines:
        return np.zeros((0, 3))
    gap = np.full((1, 3), np.nan)
    return np.concatenate([x for line in lines for x in (line, gap)][:-1])


def _surface_points(sf: np.ndarray, si: np.ndarray, s: int, extent: float, cut: int) -> np.ndarray:
    """World points of surface ``s`` along its intersection with the plane p[cut] = 0."""
    rot = sf[s, G.R00 : G.R22 + 1].reshape(3, 3)
    o = sf[s, G.OX : G.OZ + 1]
    shape = si[s, G.SHAPE]
    if shape in (G.SHAPE_CONIC, G.SHAPE_QUADRIC):
        rmax = min(math.sqrt(sf[s, G.RMAX2]), extent)
        c, k = sf[s, G.CURV], sf[s, G.CONIC]
        # the meridian in the plane: local direction (cos ψ, sin ψ, 0) whose world p[cut] vanishes
        psi = math.atan2(-rot[0, cut], rot[1, cut])
        if shape == G.SHAPE_QUADRIC:  # that meridian of an astigmatic quadric is a conic
            c_psi = c * math.cos(psi) ** 2 + sf[s, G.CURV_Y] * math.sin(psi) ** 2
            c, k = c_psi, (1.0 + k) * c / c_psi - 1.0
        r = np.linspace(-rmax, rmax, 801)
        z = sag(c, k, np.abs(r))
        local = np.stack([r * math.cos(psi), r * math.sin(psi), z], 1)
        return local @ rot + o
    if shape == G.SHAPE_LASHES:
        return _lash_points(sf, s, rot, o, cut)
    if shape == G.SHAPE_SPHERE:
        rad = sf[s, G.RADIUS]
        if abs(o[cut]) >= rad:
            return np.zeros((0, 3))
        rc = math.sqrt(rad * rad - o[cut] ** 2)
        a = np.linspace(0.0, 2 * math.pi, 721)
        pts = np.zeros((a.size, 3))
        pts[:, 1 - cut] = o[1 - cut] + rc * np.cos(a)
        pts[:, 2] = o[2] + rc * np.sin(a)
        return pts
    # cylinder: points (R cos a, R sin a, h) local; solve world p[cut] = 0 for h (axis not ⟂)
    rad = sf[s, G.RADIUS]
    ax = rot[2]
    a = np.linspace(0.0, 2 * math.pi, 721)
    ring = rad * (np.outer(np.cos(a), rot[0]) + np.outer(np.sin(a), rot[1]))
    if abs(ax[cut]) > 1e-9:
        h = -(o[cut] + ring[:, cut]) / ax[cut]
        return o + ring + np.outer(h, ax)
    # axis in the section plane: two lines along the axis where the ring crosses the plane
    lines = []
    h = np.linspace(sf[s, G.ZLO], sf[s, G.ZHI], 201)
    base = np.arctan2(-rot[0, cut], rot[1, cut])
    for ang in np.unique(np.round(base + np.array([0, math.pi]), 12)):
        p = o + rad * (math.cos(ang) * rot[0] + math.sin(ang) * rot[1])
        if abs(p[cut]) < 1e-6:
            lines.append(p + np.outer(h, ax))
    if not lines:
        return np.zeros((0, 3))
    gap = np.full((1, 3), np.nan)  # not a point: the caller's clip mask splits the lines there
    return np.concatenate([x for line in lines for x in (line, gap)][:-1])


def world_table(cs: CompiledScene) -> np.ndarray:
    """The surface table ``sf`` with each surface's placement (origin, rotation, bounding
    sphere and a group's sphere) turned from the camera frame back to the world frame."""
    f = cs.frame
    sf = cs.sf.copy()
    if f.is_identity:
        return sf
    for s in range(sf.shape[0]):
        rot = sf[s, G.R00 : G.R22 + 1].reshape(3, 3) @ f.rotation  # local = rot_c R (p_w − o_w)
        sf[s, G.R00 : G.R22 + 1] = rot.ravel()
        sf[s, G.OX : G.OZ + 1] = f.world_point(sf[s, G.OX : G.OZ + 1])
        sf[s, G.BX : G.BZ + 1] = f.world_point(sf[s, G.BX : G.BZ + 1])
        if cs.si[s, G.GROUP_END] > s:
            sf[s, G.GBX : G.GBZ + 1] = f.world_point(sf[s, G.GBX : G.GBZ + 1])
    return sf


def _meridian(cs: CompiledScene, vertical: int) -> np.ndarray:
    """Unit camera-frame direction across the lens axis closest to the view's vertical axis."""
    e = np.zeros(3)
    e[vertical] = 1.0
    m = cs.frame.vector(e)
    m[2] = 0.0
    n = float(np.linalg.norm(m))
    return m / n if n > 1e-9 else np.array([1.0, 0.0, 0.0])


def _camera_sections(cs: CompiledScene, cut: int, vertical: int) -> list[Section]:
    """The lens surfaces, stop, sensor and field of view, in the camera's meridian closest to
    the view, turned to the world and projected onto the view."""
    m = _meridian(cs, vertical)
    out: list[Section] = []

    def add(name: str, category: str, r: np.ndarray, z: np.ndarray) -> None:
        pts = cs.frame.world_point(np.outer(r, m) + np.outer(z, [0.0, 0.0, 1.0]))
        out.append(Section(name, category, pts[:, 2], pts[:, vertical]))

    for j in range(cs.lf.shape[0]):
        sd = cs.lf[j, Q.L_SD]
        c, k = cs.lf[j, Q.L_CURV], cs.lf[j, Q.L_CONIC]
        if j == cs.stop_index:
            for sign in (1.0, -1.0):
                ring = sign * np.array([sd, sd + max(8.0 * sd / 26.0, 0.3)])
                add("aperture stop", "stop", ring, np.full(2, cs.lf[j, Q.L_Z]))
            if cs.lf[j, Q.L_POWER] == 0.0:
                continue
        r = np.linspace(-sd, sd, 201)
        add(f"lens S{j + 1}", "lens", r, cs.lf[j, Q.L_Z] + sag(c, k, np.abs(r)))
        nxt = j + 1
        if nxt < cs.lf.shape[0] and cs.lf[j, Q.L_N1] > 1.0 + 1e-6:
            # glass between S(j+1) and S(j+2): the element's edges close its outline
            sd2 = cs.lf[nxt, Q.L_SD]
            c2, k2 = cs.lf[nxt, Q.L_CURV], cs.lf[nxt, Q.L_CONIC]
            z1 = cs.lf[j, Q.L_Z] + sag(c, k, np.array([sd]))[0]
            z2 = cs.lf[nxt, Q.L_Z] + sag(c2, k2, np.array([sd2]))[0]
            for sign in (1.0, -1.0):
                add(f"lens S{j + 1}-S{nxt + 1} edge", "lens",
                    sign * np.array([sd, sd2]), np.array([z1, z2]))  # fmt: skip
    w, h = cs.picture.width_mm, cs.picture.height_mm
    half = math.hypot(w * m[0], h * m[1]) / 2  # the picture's half-extent along the meridian
    add("sensor", "sensor", np.array([-half, half]), np.full(2, cs.image_z))
    fo = cs.first_order
    edge = half / abs(fo.magnification)  # the imaged field's half-extent on the object plane
    for sign in (1.0, -1.0):
        add(
            "field of view",
            "field",
            np.array([0.0, sign * edge]),
            np.array([fo.entrance_pupil_z, 0.0]),
        )
    return out


def _body_outline(
    pieces: list[np.ndarray], name: str = "camera body", category: str = "camera"
) -> list[Section]:
    """A closed body's section (the camera's body, an LED's cylinder) as one closed outline:
    the convex hull of its faces' cut pieces (the body is a cylinder, convex, so its section
    is too; the front ring alone cuts to two parallel strokes). Pieces that span no area are
    drawn as they are."""
    if not pieces:
        return []
    from scipy.spatial import ConvexHull, QhullError

    pts = np.concatenate(pieces)
    try:
        hull = pts[ConvexHull(pts).vertices]
    except (QhullError, ValueError):
        return [Section(name, category, p[:, 0], p[:, 1]) for p in pieces]
    ring = np.vstack([hull, hull[:1]])
    return [Section(name, category, ring[:, 0], ring[:, 1])]


#: Tissues drawn only in front of the periorbital skin: behind it they are inside the head.
_BEHIND_SKIN_HIDDEN = ("upper eyelid", "lower eyelid", "brow", "cheek", "nose")


def _skin_front(cs: CompiledScene, sf: np.ndarray, emit: np.ndarray) -> tuple[float, float] | None:
    """(world z of the periorbital skin plane, +1 or −1: the side of the LEDs), or None when
    the scene has no flat skin facing ±z (then nothing is clipped)."""
    if "periorbital skin" not in cs.surface_names:
        return None
    s = cs.surface_names.index("periorbital skin")
    normal = sf[s, G.R20 : G.R22 + 1]
    if cs.si[s, G.SHAPE] != G.SHAPE_CONIC or sf[s, G.CURV] != 0.0 or abs(normal[2]) < 0.999:
        return None
    z0 = float(sf[s, G.OZ])
    side = 1.0 if len(emit) == 0 or float(np.mean(emit[:, 2])) >= z0 else -1.0
    return z0, side


def _closed_body(name: str, category: str, names: list[str]) -> str | None:
    """The closed body a surface is a face of, drawn as one outline: ``"camera body"`` for
    the camera's, ``"LED k body"`` for the three faces of LED k's cylinder; None otherwise."""
    if category == "camera":
        return "camera body"
    own = name.split(" (")[0]  # "LED 3 body (side)" → "LED 3 body"
    if category == "led" and (own != name or f"{own} (side)" in names):
        return own
    return None


def system_sections(cs: CompiledScene, extent: float = 60.0, view: str = "yz") -> list[Section]:
    """Every part of the system in one view (module docstring), world mm: the eye and face
    surfaces and LED bodies cut by the view's plane, the LEDs' axes (10 mm), the camera, its
    field of view, and the eye-plane receiver (the world plane z = z₀ through the eye's nominal
    vertex)."""
    cut, vertical = VIEWS[view]
    sf = world_table(cs)
    plane_o = eye_plane_origin(cs.scene)  # the eye's nominal vertex: the cut passes through it
    if plane_o[cut]:
        sf[:, G.OX + cut] -= plane_o[cut]
        sf[:, G.BX + cut] -= plane_o[cut]
    out: list[Section] = []
    # the cut pieces (z, vertical) of each closed body (the camera's, an LED's cylinder)
    closed: dict[tuple[str, str], list[np.ndarray]] = {}
    emit = cs.frame.world_point(cs.led.points)
    front = _skin_front(cs, sf, emit)
    for s, name in enumerate(cs.surface_names):
        if cs.si[s, G.ACTION] == G.ACT_LENS:
            continue  # drawn with the camera below
        pts = _surface_points(sf, cs.si, s, extent, cut)
        if len(pts) == 0:
            continue
        keep = _clip_mask(sf, s, pts) & (np.abs(pts[:, vertical]) <= extent)
        if front is not None and name in _BEHIND_SKIN_HIDDEN:
            # inside the head, behind the skin: the tissue there is neither seen nor drawn
            z0, side = front
            keep &= side * (pts[:, 2] - z0) >= -1e-9
        for run in _runs(pts, keep):
            category = _category(name, int(cs.si[s, G.ACTION]))
            whole = _closed_body(name, category, cs.surface_names)
            if whole is not None:
                closed.setdefault((whole, category), []).append(run[:, [2, vertical]])
                continue
            out.append(Section(name, category, run[:, 2], run[:, vertical]))
    for (whole, category), pieces in closed.items():
        out.extend(_body_outline(pieces, whole, category))
    axes = cs.frame.world_vector(cs.led.axes)
    for k, (p, a) in enumerate(zip(emit, axes, strict=True)):
        line = np.stack([p, p + 10.0 * a])
        out.append(Section(f"LED {k} axis", "led", line[:, 2], line[:, vertical]))
    out.extend(_camera_sections(cs, cut, vertical))
    half = (cs.eye_plane.height_mm if vertical == 1 else cs.eye_plane.width_mm) / 2
    out.append(
        Section(
            "eye plane",
            "receiver",
            np.full(2, plane_o[2]),
            plane_o[vertical] + np.array([-half, half]),
        )
    )
    return out
