"""Checks of a drawn matplotlib figure from matplotlib's own extents (used by test_figures.py).

- :func:`text_overlaps`: every pair of drawn, non-empty text elements (titles, suptitle, axis
  labels, tick labels that are drawn, colour-bar labels, annotations, legend entries) whose
  window extents (``Text.get_window_extent`` with the canvas renderer) intersect by more than
  ``tolerance_px`` in both directions.
- :func:`images_without_unit_colorbar`: every image panel (``AxesImage`` or ``QuadMesh``) whose
  colour scale has no colour bar (one drawn for it, or for another image of the same norm and
  colour map), or whose colour bar label names no unit in parentheses.
- :func:`axes_without_unit_label`: every axis (x or y, colour bars apart: see above) that
  draws tick labels — a numeric scale shown — whose label does not end with a unit in
  parentheses, e.g. "(mm)", "(°)", "(px)" or "(dimensionless)".
- :func:`exponent_texts`: every axis (colour bars included) that draws an offset or exponent
  text ("1e−6" over a colour bar) or a tick label in e-notation ("1.6e-08"): such numbers are
  misread; a figure scales its data to an SI-prefixed unit instead (a log scale's 10^k labels
  are allowed).
- :func:`colormaps_off_rule`: every image whose colour map breaks eyelume's rule
  (:mod:`eyelume.report.plots`): a picture on the sensor (colour bar labelled "image-plane
  irradiance" or in DN) grey, an eye-plane irradiance inferno, anything else a perceptually
  uniform viridis or the diverging map.
- :func:`caption_missing`: the figure draws no caption (its suptitle, a ``fig.text`` or, for a
  one-panel figure, the panel's title: where eyelume's writers put it) naming the scene and the
  seed (``seed N``, or ``no random seed`` for a closed-form, deterministic result).
"""

from __future__ import annotations

import re

from matplotlib.collections import QuadMesh
from matplotlib.figure import Figure
from matplotlib.text import Text

#: A colour-bar label must end with a unit in parentheses, e.g. "irradiance (W/mm²)".
UNIT = re.compile(r"\(([^()]+)\)\s*$")


def _all_axes(fig: Figure) -> list:
    out, todo = [], list(fig.axes)
    while todo:
        ax = todo.pop()
        if ax in out:
            continue
        out.append(ax)
        todo.extend(getattr(ax, "child_axes", []))
    return out


def _tick_labels(fig: Figure) -> tuple[set[int], set[int]]:
    """(ids of every tick label, ids of the tick labels matplotlib draws)."""
    every, drawn = set(), set()
    for ax in _all_axes(fig):
        for axis in (ax.xaxis, ax.yaxis):
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                every.update((id(tick.label1), id(tick.label2)))
            if not (ax.get_visible() and ax.axison and axis.get_visible()):
                continue  # a hidden axis (a twin's shared x axis) draws no tick label
            for tick in axis._update_ticks():  # the ticks inside the view
                drawn.update(
                    id(lab) for lab in (tick.label1, tick.label2)
                    if lab.get_visible() and tick.get_visible()
                )  # fmt: skip
    return every, drawn


def _drawn_texts(fig: Figure) -> list[tuple[str, object]]:
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    every, drawn = _tick_labels(fig)
    out, seen = [], set()
    for t in fig.findobj(match=Text):
        parent = getattr(t, "axes", None)
        skip = (
            id(t) in seen  # findobj can reach one text twice
            or not t.get_visible()
            or not t.get_text().strip()
            or (id(t) in every and id(t) not in drawn)
            or (parent is not None and not parent.get_visible())
        )
        seen.add(id(t))
        if skip:
            continue
        bb = t.get_window_extent(renderer)
        if bb.width > 0 and bb.height > 0:
            out.append((t.get_text(), bb))
    return out


def text_overlaps(fig: Figure, tolerance_px: float = 1.0) -> list[tuple[str, str]]:
    """Pairs of drawn text elements whose extents overlap by more than ``tolerance_px``."""
    texts = _drawn_texts(fig)
    bad = []
    for i, (a, ba) in enumerate(texts):
        for b, bb in texts[i + 1 :]:
            dx = min(ba.x1, bb.x1) - max(ba.x0, bb.x0)
            dy = min(ba.y1, bb.y1) - max(ba.y0, bb.y0)
            if dx > tolerance_px and dy > tolerance_px:
                bad.append((a, b))
    return bad


def _same_scale(a, b) -> bool:
    """Two images drawn on one colour scale: same colour map, same kind of norm and limits."""
    return (
        a.cmap.name == b.cmap.name
        and type(a.norm) is type(b.norm)
        and (a.norm.vmin, a.norm.vmax) == (b.norm.vmin, b.norm.vmax)
    )


def images_without_unit_colorbar(fig: Figure) -> list[str]:
    """Descriptions of the image panels whose colour scale has no colour bar with a unit."""
    colorbars = []
    for ax in _all_axes(fig):
        for im in [*ax.images, *(c for c in ax.collections if isinstance(c, QuadMesh))]:
            if getattr(im, "colorbar", None) is not None:
                colorbars.append(im)
    bad = []
    for ax in _all_axes(fig):
        if ax in {getattr(c.colorbar, "ax", None) for c in colorbars}:
            continue  # the colour bar's own axes
        images = [*ax.images, *(c for c in ax.collections if isinstance(c, QuadMesh))]
        for im in images:
            if not im.get_visible():
                continue
            owner = (
                im
                if im.colorbar is not None
                else next((c for c in colorbars if _same_scale(c, im)), None)
            )
            where = ax.get_title() or ax.get_ylabel() or "untitled panel"
            if owner is None:
                bad.append(f"{where!r}: an image without a colour bar")
                continue
            cax = owner.colorbar.ax
            label = cax.get_ylabel() or cax.get_xlabel()
            if not UNIT.search(label):
                bad.append(f"{where!r}: colour bar label {label!r} names no unit in parentheses")
    return bad


#: A tick label in e-notation: "1.6e-08", "2e+03", "1e−6" (matplotlib's minus sign).
_E_NOTATION = re.compile(r"\d[eE][+\-−]?\d")


def exponent_texts(fig: Figure) -> list[str]:
    """Descriptions of the axes (colour bars' included) that draw an offset text or a tick
    label in e-notation."""
    _drawn_texts(fig)
    _, drawn = _tick_labels(fig)
    bad = []
    for ax in _all_axes(fig):
        if not (ax.get_visible() and ax.axison):
            continue
        for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            title = ax.get_title() if hasattr(ax, "get_title") else ""  # not a SecondaryAxis's
            where = title or axis.get_label_text() or "untitled panel"
            offset = axis.get_offset_text()
            if axis.get_visible() and offset.get_visible() and offset.get_text().strip():
                bad.append(f"{where!r}: {name} axis draws offset text {offset.get_text()!r}")
            for t in axis.get_major_ticks() + axis.get_minor_ticks():
                for lab in (t.label1, t.label2):
                    if id(lab) in drawn and _E_NOTATION.search(lab.get_text()):
                        bad.append(f"{where!r}: {name} tick label {lab.get_text()!r}")
    return bad


#: The colour maps of eyelume's rule (eyelume.report.plots's docstring).
_SENSOR, _IRRADIANCE = {"gray"}, {"inferno"}
_OTHER = {"viridis", "viridis_r", "RdBu_r", "RdBu"}


def colormaps_off_rule(fig: Figure) -> list[str]:
    """Descriptions of the images whose colour map is not the rule's for what their colour bar
    says they show."""
    bad = []
    images = []
    for ax in _all_axes(fig):
        images += [*ax.images, *(c for c in ax.collections if isinstance(c, QuadMesh))]
    bars = [im for im in images if getattr(im, "colorbar", None) is not None]
    bar_axes = {im.colorbar.ax for im in bars}
    images = [im for im in images if im.axes not in bar_axes]  # a bar's own colour strip
    for im in images:
        owner = im if im.colorbar is not None else next(
            (c for c in bars if _same_scale(c, im)), None
        )  # fmt: skip
        if owner is None:
            continue  # images_without_unit_colorbar's
        label = (owner.colorbar.ax.get_ylabel() or owner.colorbar.ax.get_xlabel()).lower()
        if "image-plane" in label or "(dn)" in label:
            allowed, what = _SENSOR, "a picture on the sensor"
        elif "irradiance" in label:
            allowed, what = _IRRADIANCE, "an irradiance map"
        else:
            allowed, what = _OTHER, "another quantity"
        if im.cmap.name not in allowed:
            bad.append(f"{label!r}: {what} drawn with {im.cmap.name!r}, not {sorted(allowed)}")
    return bad


def caption_missing(fig: Figure, scene: str, seed: int | None) -> str | None:
    """Why the figure's caption fails to name ``scene`` and the seed, or None when it does.

    The caption is a drawn figure-level text (the suptitle or a ``fig.text``) or an axes title;
    it must contain ``scene`` and ``seed {seed}`` as a word (``no random seed`` when ``seed`` is
    None)."""
    fig.canvas.draw()
    titles = [t for ax in _all_axes(fig) if ax.get_visible()
              for t in (ax.title, ax._left_title, ax._right_title)]  # fmt: skip
    texts = [t for t in [fig._suptitle, *fig.texts, *titles] if t is not None and t.get_visible()]
    said = [" ".join(t.get_text().split()) for t in texts if t.get_text().strip()]  # unwrapped
    want = re.compile(r"\bno random seed\b" if seed is None else rf"\bseed {seed}\b")
    if any(scene in s and want.search(s) for s in said):
        return None
    return f"no caption names scene {scene!r} and {want.pattern!r}; figure-level texts: {said!r}"


def axes_without_unit_label(fig: Figure) -> list[str]:
    """Descriptions of the axes whose drawn numeric scale has no label ending with a unit in
    parentheses (colour bars' axes are :func:`images_without_unit_colorbar`'s)."""
    _drawn_texts(fig)  # draws the figure: ticks and their labels are laid out
    _, drawn = _tick_labels(fig)
    bars = set()
    for ax in _all_axes(fig):
        for im in [*ax.images, *ax.collections]:
            cb = getattr(im, "colorbar", None)
            if cb is not None:
                bars.add(cb.ax)
    bad = []
    for ax in _all_axes(fig):
        if ax in bars or not (ax.get_visible() and ax.axison):
            continue
        for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            ticks = axis.get_major_ticks() + axis.get_minor_ticks()
            shown = any(
                (id(t.label1) in drawn and t.label1.get_text().strip())
                or (id(t.label2) in drawn and t.label2.get_text().strip())
                for t in ticks
            )
            label = axis.get_label_text()
            if shown and not UNIT.search(label):
                where = ax.get_title() or "untitled panel"
                bad.append(f"{where!r}: {name} axis label {label!r} names no unit in parentheses")
    return bad
