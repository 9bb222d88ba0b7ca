"""Pictures and plots of irradiance maps and optical layouts, written as PNG files.

Three outputs, all in the package's units (lengths in mm, irradiance in W/mm²):

- :func:`save_grey_png`: an irradiance array as a plain 8-bit grey picture, the way a camera image
  looks, with bright glints allowed to saturate.
- :func:`save_irradiance_plot`: the same kind of array as a labelled figure with millimetre axes and
  a colour bar in physical units.
- :func:`save_layout`: a y–z cross-section (x = 0) of the whole system, surfaces and rays, like a
  lens-design layout plot.
- :func:`save_error_time_plot`: relative error against wall time of Monte Carlo runs, log–log
  (the convergence curves of ``benchmarks/eye_image.py``).

Figures are :class:`matplotlib.figure.Figure` objects drawn by the Agg canvas; pyplot is never
imported, so nothing leaks between calls or processes. Parent directories of ``path`` are created
when missing.

**Colour maps, one rule for every figure eyelume writes** (the constants below; the figure
tests check it, ``tests/report/figure_checks.py``):

- a picture on the sensor, as the camera shows it (the eye image's irradiance on the image plane,
  the camera's digital numbers): grey, :data:`CMAP_SENSOR` (black = 0);
- a physical irradiance map that is not a camera picture (the eye-plane receiver's pattern, a
  target): the perceptually uniform :data:`CMAP_IRRADIANCE` (``inferno``);
- any other non-negative quantity (errors as magnitudes, counts, merits): the perceptually
  uniform :data:`CMAP_MAGNITUDE` (``viridis``; reversed where lower is better);
- a signed quantity (a difference, a signed error): the diverging :data:`CMAP_SIGNED`, centred
  on zero.

**Numbers without exponents**: a colour bar or axis in watts is scaled to an SI-prefixed unit
(:func:`si_scale`: µW/mm², nW, …) so that its tick labels are plain numbers and no offset text
("1e−6" over the bar) is drawn.
"""

from __future__ import annotations

import io
import math
import os
import re
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import FuncFormatter
from PIL import Image
from PIL.PngImagePlugin import PngInfo

__all__ = [
    "CATEGORY_COLORS",
    "CMAP_IRRADIANCE",
    "CMAP_MAGNITUDE",
    "CMAP_SENSOR",
    "CMAP_SIGNED",
    "si_scale",
    "agg_figure",
    "observe_figures",
    "save_figure",
    "SectionCurve",
    "add_pixel_axes",
    "wrap_title",
    "draw_maps",
    "pixel_pitch_label",
    "plain_number",
    "save_error_time_plot",
    "save_grey_png",
    "save_irradiance_plot",
    "save_layout",
]

#: Line colour of each :attr:`SectionCurve.category`, in the legend's order.
CATEGORY_COLORS: dict[str, str] = {
    "led": "tab:red",
    "eye": "tab:blue",
    "tissue": "tab:brown",
    "lens": "tab:green",
    "camera": "dimgray",
    "element": "tab:cyan",
    "stop": "black",
    "sensor": "tab:purple",
    "receiver": "tab:gray",
    "field": "tab:purple",
}

_CATEGORY_STYLES: dict[str, str] = {"receiver": "--", "field": ":"}

#: The colour maps of the rule in the module docstring.
CMAP_SENSOR = "gray"
CMAP_IRRADIANCE = "inferno"
CMAP_MAGNITUDE = "viridis"
CMAP_SIGNED = "RdBu_r"

#: SI prefixes from 1 down to 1e-15, for :func:`si_scale`.
_PREFIXES = (("", 1.0), ("m", 1e-3), ("µ", 1e-6), ("n", 1e-9), ("p", 1e-12), ("f", 1e-15))
_UNIT_AT_END = re.compile(r"\(([^()]+)\)\s*$")
_DEFAULT_RAY_COLOR = "tab:orange"
_DPI = 150

PathLike = str | os.PathLike[str]


# --------------------------------------------------------------------------------------------------
# Helpers
# --------------------------------------------------------------------------------------------------


def _finite_2d(values: np.ndarray, what: str) -> np.ndarray:
    """Return ``values`` as a 2-D float64 array, or raise if it is not 2-D or not finite."""
    arr = np.asarray(values, dtype=np.float64)
    if arr.ndim != 2:
        raise ValueError(f"{what} must be a 2-D array, got shape {arr.shape}")
    bad = int(np.count_nonzero(~np.isfinite(arr)))
    if bad:
        raise ValueError(
            f"{what} has {bad} non-finite value(s) (NaN or inf) out of {arr.size}; "
            "mask or replace them before writing a picture"
        )
    return arr


def _check_percentile(clip_percentile: float) -> float:
    p = float(clip_percentile)
    if not (0.0 < p <= 100.0):
        raise ValueError(f"clip_percentile must be in (0, 100], got {clip_percentile!r}")
    return p


def _positive_percentile(arr: np.ndarray, clip_percentile: float) -> float:
    """The ``clip_percentile`` percentile of the positive entries of ``arr`` (0 if none)."""
    positive = arr[arr > 0.0]
    if positive.size == 0:
        return 0.0
    return float(np.percentile(positive, clip_percentile))


def _prepare_path(path: PathLike) -> Path:
    out = Path(os.fspath(path))
    out.parent.mkdir(parents=True, exist_ok=True)
    return out


def si_scale(label: str, largest: float) -> tuple[float, str]:
    """(factor, label) to draw values up to ``largest`` in an SI-prefixed unit: a ``label``
    ending with a unit in watts in parentheses, e.g. ``"irradiance (W/mm²)"`` with ``largest``
    = 3.2e-8, gives ``(1e-9, "irradiance (nW/mm²)")``; divide the values by ``factor``. The
    prefix is the largest of m, µ, n, p, f (down to 1e-15) that keeps ``largest`` ≥ 1 in it, so
    tick labels are plain numbers below 1000. A label whose unit is not in W (or a ``largest``
    ≤ 0, NaN or ≥ 1) is returned unchanged with factor 1.

    >>> si_scale("irradiance (W/mm²)", 3.2e-8)
    (1e-09, 'irradiance (nW/mm²)')
    >>> si_scale("signal (DN)", 700.0)
    (1.0, 'signal (DN)')
    """
    m = _UNIT_AT_END.search(label)
    if m is None or not m.group(1).startswith("W") or not (0.0 < largest < 1.0):
        return 1.0, label
    prefix, factor = next(((p, f) for p, f in _PREFIXES if largest >= f), _PREFIXES[-1])
    return factor, label[: m.start(1)] + prefix + label[m.start(1) :]


def agg_figure(width_in: float, height_in: float, layout: str | None = "constrained") -> Figure:
    """A new figure (inches) on its own Agg canvas, outside pyplot's global state; constrained
    layout by default, so titles, labels and colour bars do not collide."""
    fig = Figure(figsize=(width_in, height_in), layout=layout)
    FigureCanvasAgg(fig)
    return fig


#: Callables told of every figure eyelume writes (see :func:`observe_figures`).
_OBSERVERS: list[Callable[[Figure, str], None]] = []


@contextmanager
def observe_figures(callback: Callable[[Figure, str], None]) -> Iterator[None]:
    """Within the block, call ``callback(fig, name)`` for every figure written through
    :func:`save_figure` (every matplotlib figure eyelume writes), after it is drawn and saved
    and before it is released, so a test can inspect its final layout (text extents, colour
    bars). ``name`` is the file name, or ``"<buffer>"`` for an in-memory PNG."""
    _OBSERVERS.append(callback)
    try:
        yield
    finally:
        _OBSERVERS.remove(callback)


def literal_texts(fig: Figure) -> None:
    """Draw every text of ``fig`` that eyelume or the user wrote (titles, captions, axis labels,
    legends, cell numbers: scene, study and note names among them) as typed, not as matplotlib
    mathtext: a name such as ``Rig A: $1.5k vs $2k`` would otherwise be garbled and one such
    as ``rig $\\badcmd$`` makes drawing raise ``ParseFatalException``. Tick labels and axis
    offset texts (matplotlib's own, which may use mathtext for exponents) are left alone; eyelume
    writes no mathtext of its own."""
    from matplotlib.text import Text

    automatic: set[int] = set()
    for ax in fig.axes:
        for axis in (getattr(ax, n, None) for n in ("xaxis", "yaxis", "zaxis")):
            if axis is None:
                continue
            automatic.add(id(axis.offsetText))
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                automatic.update((id(tick.label1), id(tick.label2)))
    for text in fig.findobj(Text):
        if id(text) not in automatic:
            text.set_parse_math(False)


def save_figure(fig: Figure, path: PathLike | io.BytesIO, *, dpi: float = _DPI) -> None:
    """Render ``fig`` with the Agg canvas as a PNG to ``path`` (a file, parent folders created,
    or a binary buffer), tell the observers (:func:`observe_figures`) and release it."""
    FigureCanvasAgg(fig)
    literal_texts(fig)
    try:
        if isinstance(path, io.IOBase):
            fig.savefig(path, dpi=dpi, bbox_inches="tight", format="png")
            name = "<buffer>"
        else:
            target = _prepare_path(path)
            fig.savefig(target, dpi=dpi, bbox_inches="tight", format="png")
            name = target.name
        for observer in list(_OBSERVERS):
            observer(fig, name)
    finally:
        fig.clear()


def _save_figure(fig: Figure, path: PathLike) -> None:
    save_figure(fig, path)


# --------------------------------------------------------------------------------------------------
# Grey picture
# --------------------------------------------------------------------------------------------------


def save_grey_png(
    irradiance: np.ndarray,
    path: PathLike,
    *,
    clip_percentile: float = 99.5,
    min_width_px: int = 640,
    white: float | None = None,
) -> None:
    """Write a 2-D irradiance array as an 8-bit grey PNG a person can look at.

    The grey level is linear in irradiance,

    .. math:: g = \\operatorname{round}\\bigl(255 \\,\\min(1, \\max(0, E / E_c))\\bigr),

    from black at ``E = 0`` to white at the clip value ``E_c``, the ``clip_percentile``
    percentile of the strictly positive entries. Anything brighter than ``E_c`` saturates to white:
    small bright features such as corneal glints are clipped on purpose, because a scale running to
    the maximum would leave the face and pupil nearly black next to a glint. Negative entries are
    drawn black. Use ``clip_percentile=100`` for a scale to the maximum, or ``white`` for a fixed
    clip value (a camera's full scale, so that exposure and saturation show as they are).

    Parameters
    ----------
    irradiance : numpy.ndarray
        2-D array of shape (rows, cols), any unit (typically W/mm²). Row 0 is the top of the
        picture, column 0 its left edge.
    path : str or os.PathLike
        Output PNG file; parent directories are created when missing.
    clip_percentile : float, optional
        Percentile in (0, 100] of the positive values that maps to white. Default 99.5.
    min_width_px : int, optional
        The picture is enlarged by the smallest integer nearest-neighbour factor that makes it at
        least this many pixels wide (each array element becomes a square block), so a small
        detector image is not a thumbnail. Default 640. The factor is written in the PNG's
        ``Comment`` text chunk ("… each element drawn as a 8 x 8 pixel block").
    white : float, optional
        A fixed clip value ``E_c`` (> 0, same unit as the array); ``clip_percentile`` is then
        ignored. Default: the percentile.

    Raises
    ------
    ValueError
        If the array is not 2-D, holds NaN or inf (the message gives how many), or an option is
        out of range.

    Notes
    -----
    An all-zero array (or one with no positive entry) gives a black picture. An empty array
    (zero rows or columns) gives a black picture one element high and wide, enlarged as above.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from PIL import Image
    >>> with tempfile.TemporaryDirectory() as d:
    ...     p = pathlib.Path(d) / "eye.png"
    ...     save_grey_png(np.ones((15, 21)), p, min_width_px=100)
    ...     Image.open(p).size
    (105, 75)
    """
    arr = _finite_2d(irradiance, "irradiance")
    p = _check_percentile(clip_percentile)
    if int(min_width_px) != min_width_px or min_width_px < 1:
        raise ValueError(f"min_width_px must be a positive integer, got {min_width_px!r}")

    if white is not None and not (math.isfinite(white) and white > 0):
        raise ValueError(f"white must be a finite value > 0, got {white!r}")

    if arr.size == 0:
        grey = np.zeros((1, 1), dtype=np.uint8)
    else:
        clip = _positive_percentile(arr, p) if white is None else float(white)
        if clip > 0.0:
            scaled = np.clip(arr / clip, 0.0, 1.0) * 255.0
            grey = np.rint(scaled).astype(np.uint8)
        else:
            grey = np.zeros(arr.shape, dtype=np.uint8)

    factor = max(1, math.ceil(int(min_width_px) / grey.shape[1]))
    if factor > 1:
        grey = np.repeat(np.repeat(grey, factor, axis=0), factor, axis=1)

    # the enlargement said in the file (PNG text chunk), for whoever opens it later
    info = PngInfo()
    info.add_text(
        "Comment",
        f"eyelume: {grey.shape[1] // factor} x {grey.shape[0] // factor} array, each element "
        f"drawn as a {factor} x {factor} pixel block (nearest neighbour)",
    )
    Image.fromarray(np.ascontiguousarray(grey)).save(
        _prepare_path(path), format="PNG", pnginfo=info
    )


# --------------------------------------------------------------------------------------------------
# Irradiance figure
# --------------------------------------------------------------------------------------------------


def plain_number(value: float, _pos: int | None = None) -> str:
    """A tick label without exponent or offset (``1000``, ``0.25``; 6 significant digits)."""
    return f"{value:.6g}"


def wrap_title(text: str, width_in: float, points: float = 12.0) -> str:
    """``text`` with each of its lines wrapped to about ``width_in`` inches of a ``points`` font
    (a long scene name must not widen the figure)."""
    import textwrap

    chars = max(20, int(width_in * 120 / points))
    return "\n".join(textwrap.fill(line, chars) for line in text.split("\n"))


def add_pixel_axes(ax, shape: tuple[int, int], extent: tuple[float, float, float, float],
                   *, what: str = "px") -> None:  # fmt: skip
    """A second scale on ``ax`` counting the array's columns (top edge) and rows (left edge,
    outside the first scale: the right edge is the colour bar's) for an image of ``shape``
    (rows, cols) drawn at ``extent`` (left, right, bottom, top) mm; 0 at the left and top edges.
    ``what`` names the unit, e.g. ``"sensor px"``."""
    rows, cols = shape
    left, right, bottom, top = extent
    sx, sy = cols / (right - left), rows / (top - bottom)
    top_ax = ax.secondary_xaxis(
        "top", functions=(lambda x: (x - left) * sx, lambda c: left + c / sx)
    )
    top_ax.set_xlabel(f"column ({what} of {cols})")
    left_ax = ax.secondary_yaxis(-0.2, functions=(lambda y: (top - y) * sy, lambda r: top - r / sy))
    left_ax.set_ylabel(f"row ({what} of {rows})")


def draw_maps(  # noqa: PLR0913 - each option is one labelled aspect
    fig: Figure,
    axes: Sequence,
    arrays: Sequence[np.ndarray],
    *,
    extent: tuple[float, float, float, float] | None,
    cmap: str,
    label: str,
    vmax: float,
    clipped: bool = False,
    xlabel: str,
    ylabel: str,
    fontsize: float = 8,
) -> None:
    """Draw ``arrays`` into ``axes`` (one each) on one colour scale 0 … ``vmax`` with one colour
    bar labelled ``label`` (SI-prefixed when in watts, :func:`si_scale`; an arrow at its top
    when ``clipped``), at ``extent`` (left, right, bottom, top) mm, or in array columns and
    rows when None; ``xlabel`` on each panel, ``ylabel`` on the first."""
    vmax = float(vmax) if vmax > 0 else 1.0
    factor, label = si_scale(label, vmax)
    image = None
    for ax, arr in zip(axes, arrays, strict=True):
        image = ax.imshow(np.asarray(arr) / factor, cmap=cmap, vmin=0, vmax=vmax / factor,
                          extent=extent, interpolation="nearest")  # fmt: skip
        ax.set_xlabel(xlabel, fontsize=fontsize)
        ax.tick_params(labelsize=fontsize - 1)
    axes[0].set_ylabel(ylabel, fontsize=fontsize)
    bar = fig.colorbar(image, ax=list(axes), extend="max" if clipped else "neither", shrink=0.9)
    bar.set_label(label, fontsize=fontsize)
    bar.formatter = FuncFormatter(plain_number)
    bar.update_ticks()
    bar.ax.tick_params(labelsize=fontsize - 1)


def pixel_pitch_label(axis: str, extent, cols: int) -> str:
    """An eye image's axis label in mm on the sensor with the pixel size said, e.g.
    ``"image x on the sensor (mm; 1 px = 0.529 mm)"``, for panels too small for a second
    (pixel) scale (:func:`add_pixel_axes`)."""
    pitch = abs(extent[1] - extent[0]) / cols
    return f"image {axis} on the sensor (mm; 1 px = {pitch:.3g} mm)"


def save_irradiance_plot(  # noqa: PLR0913 - each option is one labelled aspect
    irradiance: np.ndarray,
    path: PathLike,
    *,
    extent_mm: tuple[float, float, float, float],
    title: str,
    label: str = "irradiance (W/mm²)",
    xlabel: str = "x (mm)",
    ylabel: str = "y (mm)",
    clip_percentile: float | None = None,
    pixel_axes: bool = False,
    cmap: str = CMAP_IRRADIANCE,
    vmax: float | None = None,
) -> None:
    """Write an irradiance map (or a camera picture) as a figure with millimetre axes and a
    colour bar.

    With ``pixel_axes``, a second scale on the top and left edges counts the array's columns
    and rows (the sensor's pixels of an eye image: 0 at the left and top edges), so the picture's
    enlargement is labelled in pixels as well as in mm.

    The map is drawn with ``cmap`` (the module's colour-map rule: :data:`CMAP_IRRADIANCE` for an
    eye-plane pattern, :data:`CMAP_SENSOR` for a picture on the sensor) at its physical aspect
    ratio, the colour scale running from ``min(0, E_min)`` to ``vmax`` when given (a camera's
    full scale), else ``E_max`` or, with ``clip_percentile``, that percentile of the positive
    values; brighter entries (corneal glints) then saturate and the colour bar shows an arrow at
    its top. A unit in watts is drawn SI-prefixed (:func:`si_scale`: nW/mm², …) so the colour
    bar's numbers need no exponent. Saved at 150 dpi with a tight bounding box; a long title is
    wrapped to the figure's width.

    Parameters
    ----------
    irradiance : numpy.ndarray
        2-D array of shape (rows, cols), in the unit named by ``label``. Row 0 is drawn at ``top``,
        column 0 at ``left``.
    path : str or os.PathLike
        Output PNG file; parent directories are created when missing.
    extent_mm : tuple of 4 floats
        ``(left, right, bottom, top)`` in mm: the outer edges of the array's first and last
        columns and of its last and first rows, as matplotlib's ``imshow`` extent.
    title : str
        Figure title.
    label : str, optional
        Colour bar label, with its unit in parentheses. Default ``"irradiance (W/mm²)"``.
    xlabel, ylabel : str, optional
        Axis labels. Defaults ``"x (mm)"`` and ``"y (mm)"``.
    clip_percentile : float or None, optional
        Percentile in (0, 100] of the positive values at the top of the colour scale. ``None``
        (default) scales to the maximum.
    cmap : str, optional
        Colour map (module docstring's rule). Default :data:`CMAP_IRRADIANCE`.
    vmax : float, optional
        A fixed top of the colour scale (same unit as the array); ``clip_percentile`` is then
        ignored.

    Raises
    ------
    ValueError
        If the array is not 2-D, is empty, holds NaN or inf (the message gives how many), or the
        extent is not four finite numbers with ``left != right`` and ``bottom != top``.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as d:
    ...     p = pathlib.Path(d) / "eye_plane.png"
    ...     save_irradiance_plot(np.ones((15, 21)), p, extent_mm=(-20, 20, -15, 15),
    ...                          title="Eye plane")
    ...     p.stat().st_size > 0
    True
    """
    arr = _finite_2d(irradiance, "irradiance")
    if arr.size == 0:
        raise ValueError(f"irradiance is empty (shape {arr.shape}); nothing to plot")
    ext = tuple(float(v) for v in extent_mm)
    if len(ext) != 4 or not all(math.isfinite(v) for v in ext):
        raise ValueError(
            f"extent_mm must be 4 finite numbers (left, right, bottom, top), got {ext}"
        )
    left, right, bottom, top = ext
    if left == right or bottom == top:
        raise ValueError(f"extent_mm has zero width or height: {ext}")

    vmin = min(0.0, float(arr.min()))
    if vmax is not None:
        vmax = float(vmax)
        clipped = bool(np.any(arr > vmax))
    elif clip_percentile is None:
        vmax = float(arr.max())
        clipped = False
    else:
        vmax = _positive_percentile(arr, _check_percentile(clip_percentile))
        clipped = bool(np.any(arr > vmax))
    if vmax <= vmin:
        vmax = vmin + 1.0  # constant image: any non-degenerate scale shows it as one colour
    factor, label = si_scale(label, max(abs(vmin), abs(vmax)))

    fig = Figure(figsize=(7.0, 5.0), layout="constrained")
    ax = fig.add_subplot()
    image = ax.imshow(
        arr / factor,
        cmap=cmap,
        vmin=vmin / factor,
        vmax=vmax / factor,
        origin="upper",
        extent=(left, right, bottom, top),
        interpolation="nearest",
    )
    # The colour bar lives in an inset of the axes so it is as tall as the image at any aspect.
    # Its width, a fraction of the axes width, grows for tall images to keep it readable.
    widen = max(1.0, abs(top - bottom) / abs(right - left) / 0.75)
    cax = ax.inset_axes((1.0 + 0.04 * widen, 0.0, 0.045 * widen, 1.0))
    colorbar = fig.colorbar(image, cax=cax, extend="max" if clipped else "neither")
    colorbar.set_label(label)
    # plain numbers (the unit is SI-prefixed): no offset text on top of the bar
    colorbar.formatter = FuncFormatter(plain_number)
    colorbar.update_ticks()
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if pixel_axes:
        add_pixel_axes(ax, arr.shape, (left, right, bottom, top), what="sensor px")
        fig.suptitle(wrap_title(title, 7.0))  # above the pixel scale, not on it
    else:
        ax.set_title(wrap_title(title, 6.0))
    _save_figure(fig, path)


# --------------------------------------------------------------------------------------------------
# Layout cross-section
# --------------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class SectionCurve:
    """One surface or outline of the system, cut by the plane x = 0, in world coordinates.

    Parameters
    ----------
    name : str
        What the curve is, shown in error messages, e.g. ``"anterior cornea"``, ``"LED 1 body"``,
        ``"lens S3"``, ``"sensor"``.
    category : str
        One of ``"led"``, ``"eye"``, ``"tissue"``, ``"lens"``, ``"element"`` (an optical
        element of the scene), ``"stop"``, ``"sensor"``, ``"receiver"``; sets the colour
        (:data:`CATEGORY_COLORS`) and the legend entry.
    z : numpy.ndarray
        World z (mm) of the polyline's vertices, 1-D.
    y : numpy.ndarray
        World y (mm) of the same vertices, 1-D, same length as ``z``.
    tag : str, optional
        A short label written beside the curve's first vertex, e.g. an LED's id ``"2"`` on its
        axis (curves whose first vertices coincide share one label, ``"1, 3"``). Default none.

    Raises
    ------
    ValueError
        At construction, naming the curve, if the category is unknown, ``z`` and ``y`` are not 1-D
        arrays of the same non-zero length, or either holds NaN or inf.

    Notes
    -----
    ``z`` and ``y`` are stored as read-only float64 copies. Instances compare by identity
    (``eq=False``) since arrays have no single truth value.
    """

    name: str
    category: str
    z: np.ndarray
    y: np.ndarray
    tag: str = ""

    def __post_init__(self) -> None:
        if self.category not in CATEGORY_COLORS:
            raise ValueError(
                f"curve {self.name!r}: unknown category {self.category!r}; "
                f"expected one of {sorted(CATEGORY_COLORS)}"
            )
        z = np.array(self.z, dtype=np.float64)
        y = np.array(self.y, dtype=np.float64)
        if z.ndim != 1 or y.ndim != 1:
            raise ValueError(
                f"curve {self.name!r}: z and y must be 1-D, got shapes {z.shape} and {y.shape}"
            )
        if z.shape != y.shape:
            raise ValueError(
                f"curve {self.name!r}: z and y differ in length ({z.size} vs {y.size})"
            )
        if z.size == 0:
            raise ValueError(f"curve {self.name!r}: has no vertices")
        bad = int(np.count_nonzero(~np.isfinite(z)) + np.count_nonzero(~np.isfinite(y)))
        if bad:
            raise ValueError(f"curve {self.name!r}: {bad} non-finite value(s) (NaN or inf) in z/y")
        z.flags.writeable = False
        y.flags.writeable = False
        object.__setattr__(self, "z", z)
        object.__setattr__(self, "y", y)


def _ray_segments(rays: Sequence[np.ndarray], vertical: int = 1) -> list[np.ndarray]:
    """Each ray's (z, vertical) vertices as a (k, 2) array (vertical 1: y, 0: x), after checking
    shape and finiteness."""
    segments = []
    for i, ray in enumerate(rays):
        v = np.asarray(ray, dtype=np.float64)
        if v.ndim != 2 or v.shape[1] != 3 or v.shape[0] == 0:
            raise ValueError(
                f"ray {i}: expected a (k, 3) array of (x, y, z) vertices, got {v.shape}"
            )
        bad = int(np.count_nonzero(~np.isfinite(v)))
        if bad:
            raise ValueError(
                f"ray {i}: {bad} non-finite value(s) (NaN or inf); "
                "end escaping rays at a finite point before plotting"
            )
        segments.append(v[:, [2, vertical]])
    return segments


def _ray_colours(ray_colors: Sequence[str] | None, n: int) -> list[str]:
    if ray_colors is None:
        return [_DEFAULT_RAY_COLOR] * n
    if len(ray_colors) != n:
        raise ValueError(f"ray_colors has {len(ray_colors)} entries but there are {n} rays")
    return list(ray_colors)


def _layout_width_in(curves: Sequence[SectionCurve], segments: list[np.ndarray]) -> float:
    """The layout's width (in) for a 5 in height: the system's aspect at equal scale, 4 to 16."""
    zs = [c.z for c in curves] + [s[:, 0] for s in segments]
    vs = [c.y for c in curves] + [s[:, 1] for s in segments]
    if not zs:
        return 6.0
    span_z = float(np.ptp(np.concatenate(zs))) or 1.0
    span_v = float(np.ptp(np.concatenate(vs))) or 1.0
    return float(np.clip(4.2 * span_z / span_v + 2.2, 4.0, 16.0))


def save_layout(
    curves: Sequence[SectionCurve],
    rays: Sequence[np.ndarray],
    path: PathLike,
    *,
    title: str,
    ray_colors: Sequence[str] | None = None,
    vertical: str = "y",
    ray_legend: Sequence[tuple[str, str]] = (),
    led_bodies: Sequence[str] = ("sphere",),
) -> None:
    """Write a y–z (or x–z) cross-section of the optical system, surfaces and rays, as a
    layout plot (``vertical``: ``"y"`` or ``"x"``, the world axis drawn upward; the rays are
    projected onto that plane).

    z runs horizontally, y vertically, both in mm and at equal scale. Each curve is a line in its
    category's colour (receivers dashed), with one legend entry per category present. Each ray is
    a thin semi-transparent polyline through its vertices' (z, y), i.e. its projection onto the
    plane x = 0. The figure is 16 × 5 in at 150 dpi so a system spanning z ∈ [−30, 500] mm and
    y ∈ [−40, 40] mm stays readable; the y range is widened to fill the axes at equal scale.

    Parameters
    ----------
    curves : sequence of SectionCurve
        Surfaces and outlines, drawn in order.
    rays : sequence of numpy.ndarray
        Ray paths, each a (k, 3) array of world vertices (x, y, z) in mm, k ≥ 1 (a single vertex
        draws nothing). A (n, k, 3) array also works.
    path : str or os.PathLike
        Output PNG file; parent directories are created when missing.
    title : str
        Figure title.
    ray_colors : sequence of str or None, optional
        One matplotlib colour per ray (e.g. by LED); default all ``"tab:orange"``.
    ray_legend : sequence of (colour, label), optional
        Legend entries for the rays' colours, e.g. ``[("tab:pink", "rays reaching the
        sensor"), ("tab:orange", "other rays")]``; rays of every colour but the last entry's are
        drawn stronger and on top (the few that reach the sensor among many that do not).

    led_bodies : sequence of str, optional
        The LEDs' body shapes (``"sphere"``, ``"cylinder"``: :class:`eyelume.scene.model.LedArray`'s
        ``body_shape``), for the legend; default a sphere.

    LEDs (category ``"led"``) appear in the legend as drawn: their body's section — a circle
    for a sphere, a rectangle for a cylinder (a flat SMD package cut along its axis), both when
    both are present — and a line (its axis); their ``tag`` (the LED's id) is written beside
    each axis's start.

    Raises
    ------
    ValueError
        If a ray is not a finite (k, 3) array (the message gives its index), an entry of
        ``curves`` is not a :class:`SectionCurve`, or ``ray_colors`` differs in length from
        ``rays``. Bad curve arrays are rejected when the :class:`SectionCurve` is built.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> cornea = SectionCurve("anterior cornea", "eye", np.array([-1.0, 0.0, -1.0]),
    ...                       np.array([-5.0, 0.0, 5.0]))
    >>> ray = np.array([[0.0, 20.0, 60.0], [0.0, 2.0, 0.0], [0.0, -10.0, 200.0]])
    >>> with tempfile.TemporaryDirectory() as d:
    ...     p = pathlib.Path(d) / "layout.png"
    ...     save_layout([cornea], [ray], p, title="Layout")
    ...     p.stat().st_size > 0
    True
    """
    for curve in curves:
        if not isinstance(curve, SectionCurve):
            raise ValueError(f"curves must hold SectionCurve objects, got {type(curve).__name__}")
    if vertical not in ("x", "y"):
        raise ValueError(f"vertical must be 'x' or 'y', got {vertical!r}")
    segments = _ray_segments(rays, 1 if vertical == "y" else 0)
    colors = _ray_colours(ray_colors, len(segments))

    # the system's width at equal scale, plus the legend's column beside the axes
    fig = Figure(figsize=(_layout_width_in(curves, segments) + 3.0, 5.0), layout="constrained")
    ax = fig.add_subplot()
    if segments:
        # rays in a legend colour other than the last (the common "other" rays) stand out
        strong = {c for c, _ in ray_legend[:-1]}
        rgba = [to_rgba(c, 0.9 if c in strong else 0.35) for c in colors]
        widths = [1.0 if c in strong else 0.5 for c in colors]
        order = sorted(range(len(segments)), key=lambda i: colors[i] in strong)  # strong on top
        ax.add_collection(
            LineCollection([segments[i] for i in order], colors=[rgba[i] for i in order],
                           linewidths=[widths[i] for i in order], zorder=1),
            autolim=True,
        )  # fmt: skip
    present: list[str] = []
    tags: list[tuple[float, float, str]] = []
    for curve in curves:
        ax.plot(
            curve.z,
            curve.y,
            color=CATEGORY_COLORS[curve.category],
            linestyle=_CATEGORY_STYLES.get(curve.category, "-"),
            linewidth=1.3,
            marker="o" if curve.z.size == 1 else None,
            markersize=3,
            zorder=2,
        )
        if curve.category not in present:
            present.append(curve.category)
        if curve.tag:
            tags.append((float(curve.z[0]), float(curve.y[0]), curve.tag))
    ax.autoscale_view()
    # equal scale: a wide system (longer in z than across) widens its across range to fill the
    # axes; a narrow one shapes the axes box to the drawn content instead (widening its z range
    # drew vr-offaxis, z −25 … 57 mm, on z −90 … 125 mm, in a third of each axis)
    (z0, z1), (v0, v1) = ax.get_xlim(), ax.get_ylim()
    ax.set_aspect("equal", adjustable="datalim" if z1 - z0 >= v1 - v0 else "box")
    _write_tags(ax, tags)

    handles = _layout_handles(present, ray_legend, led_bodies)
    if handles:
        ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                  borderaxespad=0.0, fontsize="small", framealpha=0.85)  # fmt: skip
    ax.set_xlabel("world z (mm)")
    ax.set_ylabel(f"world {vertical} (mm)")
    ax.set_title(wrap_title(title, fig.get_figwidth() - 3.0))
    ax.grid(True, linewidth=0.3, alpha=0.5)
    _save_figure(fig, path)


#: An LED body shape's legend: (marker, symbol) as its section is drawn.
_LED_BODY_MARKS = {"sphere": ("o", "○"), "cylinder": ("s", "▭")}


def _layout_handles(
    present: list[str], ray_legend: Sequence[tuple[str, str]], led_bodies: Sequence[str] = ()
) -> list[Line2D]:
    """Legend entries of a layout: each category present, drawn as on the plot (an LED as its
    body's section, a circle for a sphere or a rectangle for a cylinder, on its axis line;
    one entry per body shape in ``led_bodies``), then the rays' colours."""
    handles = []
    shapes = [b for b in _LED_BODY_MARKS if b in led_bodies] or ["sphere"]
    for c in (c for c in CATEGORY_COLORS if c in present):
        entries = (
            [(_LED_BODY_MARKS[b][0], f"LED: {b} body {_LED_BODY_MARKS[b][1]}") for b in shapes]
            if c == "led"
            else [(None, c)]
        )
        if c == "led":
            marker, label = entries[-1]
            entries[-1] = (marker, f"{label}, axis —, its id")
        for marker, label in entries:
            handles.append(
                Line2D(
                    [],
                    [],
                    color=CATEGORY_COLORS[c],
                    linestyle=_CATEGORY_STYLES.get(c, "-"),
                    linewidth=1.3,
                    marker=marker,
                    markersize=5,
                    markerfacecolor="none",
                    label=label,
                )
            )
    for color, label in ray_legend:
        handles.append(Line2D([], [], color=color, linewidth=1.3, label=label))
    return handles


def _write_tags(ax, tags: list[tuple[float, float, str]]) -> None:
    """Each tag beside its point, tags of points closer than 2 % of the view joined."""
    if not tags:
        return
    (z0, z1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    near = 0.02 * max(abs(z1 - z0), abs(y1 - y0))
    groups: list[list] = []
    for z, y, tag in tags:
        for g in groups:
            if abs(g[0] - z) <= near and abs(g[1] - y) <= near:
                g[2].append(tag)
                break
        else:
            groups.append([z, y, [tag]])
    for z, y, names in groups:
        ax.annotate(
            ", ".join(names), (z, y), textcoords="offset points", xytext=(-4, 3),
            ha="right", va="bottom", fontsize=7, color=CATEGORY_COLORS["led"],
        )  # fmt: skip


# --------------------------------------------------------------------------------------------------
# Error against time
# --------------------------------------------------------------------------------------------------


def _minor_log_label(value: float, _pos: int) -> str:
    if value <= 0:
        return ""
    mantissa = value / 10 ** math.floor(math.log10(value) + 1e-9)
    return f"{value:g}" if round(mantissa, 6) in (2.0, 5.0) else ""


def save_error_time_plot(
    curves: Sequence[tuple[str, Sequence[float], Sequence[float]]],
    path: PathLike,
    *,
    title: str,
    targets: Sequence[tuple[str, float, float]] = (),
    xlabel: str = "wall time (s)",
    ylabel: str = "relative standard error (dimensionless)",
) -> None:
    """Write relative error against wall time of Monte Carlo runs as a log–log figure.

    Each curve is a line with markers through its points in the order given. Points that cannot
    be drawn on log axes (zero, negative, NaN or infinite time or error, e.g. the error of a
    pixel that received no ray) are left out, and the number left out is added to the curve's
    legend label; a curve with no drawable point still gets a legend entry saying so. Curves
    whose label starts with ``"~"`` are drawn dashed (predictions rather than measurements).
    Each target ``(label, time, error)`` is drawn as a star, with dotted lines
    bounding the region "at most this error in at most this time". A guide line of slope −½
    (error ∝ 1/√time, the Monte Carlo rate) runs through the first drawable point of the first
    curve.

    Parameters
    ----------
    curves : sequence of (label, times, errors)
        Times in seconds and relative errors (dimensionless), equal lengths.
    path : str or os.PathLike
        Output PNG file; parent directories are created when missing.
    title : str
        Figure title.
    targets : sequence of (label, time, error), optional
        Targets to mark.
    xlabel, ylabel : str, optional
        Axis labels.

    Raises
    ------
    ValueError
        If a curve's times and errors differ in length, or no curve has a drawable point.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> with tempfile.TemporaryDirectory() as d:
    ...     p = pathlib.Path(d) / "curve.png"
    ...     save_error_time_plot([("fast", [1, 2, 4], [0.01, 0.007, 0.005])], p, title="Curve",
    ...                          targets=[("goal", 1.0, 0.01)])
    ...     p.stat().st_size > 0
    True
    """
    fig = Figure(figsize=(7.0, 5.0), layout="constrained")
    ax = fig.add_subplot()
    ax.set_xscale("log")
    ax.set_yscale("log")
    first: tuple[float, float] | None = None
    drawn = 0
    for label, times, errors in curves:
        t = np.asarray(times, dtype=np.float64).ravel()
        e = np.asarray(errors, dtype=np.float64).ravel()
        if t.shape != e.shape:
            raise ValueError(
                f"curve {label!r}: {t.size} times but {e.size} errors; they must pair up"
            )
        ok = np.isfinite(t) & np.isfinite(e) & (t > 0) & (e > 0)
        dropped = int(t.size - ok.sum())
        if not ok.any():
            ax.plot([], [], linestyle="none", label=f"{label} (no drawable point of {t.size})")
            continue
        shown = label + (f" ({dropped} point(s) not drawable)" if dropped else "")
        ax.plot(
            t[ok],
            e[ok],
            marker="o",
            markersize=4,
            linewidth=1.3,
            linestyle="--" if label.startswith("~") else "-",
            label=shown,
        )
        drawn += 1
        if first is None:
            first = (float(t[ok][0]), float(e[ok][0]))
    if drawn == 0:
        raise ValueError("no curve has a point with finite, positive time and error")
    for label, t_max, e_max in targets:
        ax.plot([t_max], [e_max], marker="*", markersize=12, color="black", linestyle="none")
        ax.annotate(
            label, (t_max, e_max), textcoords="offset points", xytext=(6, 6), fontsize="small"
        )
        ax.axhline(e_max, color="black", linestyle=":", linewidth=0.8)
        ax.axvline(t_max, color="black", linestyle=":", linewidth=0.8)
    if first is not None:
        x0, y0 = first
        lo, hi = ax.get_xlim()
        xs = np.array([lo, hi])
        ax.plot(
            xs,
            y0 * np.sqrt(x0 / xs),
            color="grey",
            linewidth=0.8,
            alpha=0.6,
            label="slope −½ (error ∝ 1/√time)",
        )
        ax.set_xlim(lo, hi)
    # plain numbers; of the minor ticks only 2 and 5 of each decade are labelled (3, 4, … collide)
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(FuncFormatter(_minor_log_label))
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, which="both", linewidth=0.3, alpha=0.5)
    ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    _save_figure(fig, path)
