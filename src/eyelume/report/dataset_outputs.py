"""What a labelled dataset folder (``eyelume dataset``) becomes for its users: an OpenEDS-layout
copy, a contact sheet of labelled pictures, the distributions of what was varied.

This module only reads the folder ``eyelume dataset`` wrote (``labels.jsonl``, ``dataset.json``,
``images/``, ``segmentation/``; the layout and the label line are ``/work/dataset_spec.md``'s,
documented in the README's *Datasets* section): it renders nothing.

OpenEDS export (:func:`export_openeds`)
---------------------------------------
Matched to the semantic-segmentation part of OpenEDS 2019 (Garbin et al. 2019, "OpenEDS: Open
Eye Dataset", arXiv:1905.03702) as the loaders trained on it read it (RITnet, the challenge's
winner, reads ``<root>/<split>/images/<stem>.png`` and ``<root>/<split>/labels/<stem>.npy``):

* ``OUT/<split>/images/<stem>.png``: 8-bit grey PNG, 640 columns × 400 rows (OpenEDS' size);
* ``OUT/<split>/labels/<stem>.npy``: uint8 array (400, 640) of class ids 0 background, 1 sclera,
  2 iris, 3 pupil — OpenEDS' ids and nothing else;
* ``<stem>`` is the picture's index in 6 digits (``000123``), the dataset's own stem.

What differs, and what was decided:

* **Size.** Our pictures have the camera's size (e.g. 400 × 400), not 640 × 400. A model trained
  on OpenEDS takes 640 × 400 input, so by default each picture is scaled by one factor
  s = min(640 / cols, 400 / rows) (aspect kept: no eye is squeezed) and centred on a black
  640 × 400 canvas (label 0, background, in the padding). A 400 × 400 picture is not resampled
  at all (s = 1: 120 black columns each side). The picture is resampled with OpenCV's area
  average when s < 1 and bilinear when s > 1; the labels with nearest neighbour (ids stay ids).
  ``size=None`` keeps each picture's own size instead (for code that resizes itself).
  ``OUT/eyelume_export.json`` records, per picture, ``scale`` and ``offset_px`` with
  x_export = s · (x + ½) − ½ + offset_x (same for y; pixel centres, the OpenCV convention of
  the labels), so the label file's ellipses and glints map onto the exported pictures.
* **Grey levels.** OpenEDS pictures are 8-bit. An 8-bit dataset picture is copied; a 16-bit one
  (DN as is) is scaled by 255 / (2^b − 1), b the sensor's ADC bits when ``dataset.json``
  records ``adc_bits`` (top level or under ``sensor``), else the smallest b ≥ 8 that holds that
  picture's largest DN (said in ``eyelume_export.json``).
* **Classes.** The OpenEDS view of eyelume's segmentation (ids 0–7, ``segmentation/*.png``):
  skin (4) and eyelid (5) → 0 background (OpenEDS' annotators marked only sclera, iris and
  pupil); a glint (6) or spurious reflection (7) pixel → the class under it. ``eyelume
  dataset`` writes that map exactly (``segmentation_openeds/``, named by the label line's
  ``segmentation_openeds``: :func:`eyelume.analysis.labels.openeds_map` with the scene's
  primary surface map) and the export copies it as is. Only a label line without it (a
  dataset made before it was written) is mapped here, a glint or reflection pixel taking the
  class (after 4, 5 → 0) of the nearest pixel that is neither 6 nor 7 (exact Euclidean
  distance transform). The error is confined to the pixels of a glint or reflection that
  straddles a class boundary (pupil/iris, iris/sclera, a lid margin): within it the mapped
  boundary is the line equidistant from the two classes outside it instead of the true one,
  so a pixel may be wrong by at most the spot's diameter (a few pixels for a glint).
* **Content.** OpenEDS pictures are of real people under the headset's own LEDs; ours are
  renders: no motion blur, no make-up, no tear film. Only ``train`` (or the ``split`` named) is
  written; OpenEDS' other parts (sequences, key points, gaze) are not.

Contact sheet and distributions
-------------------------------
:func:`save_contact_sheet`: N pictures spread evenly over the dataset, in DN on one grey scale
(the colour-map rule of :mod:`eyelume.report.plots`), with the labels drawn on them: the
pupil ellipse (cyan) and iris ellipse (yellow), each glint's true position as a ring with its
LED id beside it (filled red: visible; white ×: saturated; open grey: hidden or off the cornea),
spurious reflections as magenta + and, over each picture, its index, gaze, pupil diameter,
glasses and eye openness. :func:`save_distributions`: one histogram per varied quantity — gaze
(the fixation target), pupil diameter, every ``varied`` path (a vector path one panel per
component), every numeric person parameter — and the share of pictures with glasses.

Errors: a missing or malformed ``labels.jsonl`` line, a missing or unreadable picture or
segmentation file, a segmentation whose shape is not its picture's, or a class id outside 0–7
raise :class:`~eyelume.errors.InputFileError` naming the file (and the line).
"""

from __future__ import annotations

import io
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Ellipse
from matplotlib.ticker import MaxNLocator
from PIL import Image

from eyelume.errors import InputFileError
from eyelume.report.plots import CMAP_SENSOR, agg_figure, save_figure, wrap_title

__all__ = [
    "OPENEDS_CLASSES",
    "OPENEDS_SIZE",
    "LABELS_FILE",
    "ExportSummary",
    "DatasetFolder",
    "read_dataset",
    "openeds_view",
    "export_openeds",
    "save_contact_sheet",
    "save_distributions",
    "distribution_values",
    "dataset_caption",
]

#: The label file of a dataset folder (one JSON object per picture, sorted by index).
LABELS_FILE = "labels.jsonl"
#: OpenEDS 2019's segmentation ids (Garbin et al. 2019).
OPENEDS_CLASSES = {0: "background", 1: "sclera", 2: "iris", 3: "pupil"}
#: OpenEDS 2019's picture size (columns, rows).
OPENEDS_SIZE = (640, 400)
#: eyelume's extended ids (ds-labels' ``analysis.labels.SEGMENTATION_CLASSES``) this reads.
_N_CLASSES = 8
_GLINT, _REFLECTION = 6, 7


@dataclass
class DatasetFolder:
    """A dataset folder as read: ``folder``, ``info`` (``dataset.json``, or {} when absent:
    the resolved dataset file under ``dataset``, with the eyelume version and scene hashes),
    ``labels`` (the label lines, sorted by ``index``)."""

    folder: Path
    info: dict
    labels: list[dict]

    @property
    def spec(self) -> dict:
        """The dataset file as resolved: ``dataset.json``'s ``dataset`` object (or its top
        level when it has none)."""
        inner = self.info.get("dataset")
        return inner if isinstance(inner, dict) else self.info

    @property
    def name(self) -> str:
        return str(self.spec.get("name") or self.folder.name)

    @property
    def scene(self) -> str:
        return str(self.spec.get("scene", "scene not recorded"))

    @property
    def seed(self) -> int | None:
        seed = self.spec.get("seed")
        return seed if isinstance(seed, int) and not isinstance(seed, bool) else None


def _label_line(path: Path, n: int, line: str, seen: set[int]) -> dict:
    """Line ``n`` of the label file, checked (:func:`read_dataset`)."""
    try:
        row = json.loads(line)
    except ValueError as exc:
        raise InputFileError(f"line {n} is not JSON ({exc})", file=path) from None
    if not isinstance(row, dict):
        raise InputFileError(f"line {n} is not a JSON object", file=path)
    index = row.get("index")
    if isinstance(index, bool) or not isinstance(index, int) or index < 0:
        raise InputFileError(f"line {n}: 'index' = {index!r} is not an integer >= 0", file=path)
    if not isinstance(row.get("image"), str):
        raise InputFileError(f"line {n}: 'image' = {row.get('image')!r} is no path", file=path)
    if index in seen:
        raise InputFileError(f"line {n}: picture {index} is listed twice", file=path)
    return row


def read_dataset(folder: str | Path) -> DatasetFolder:
    """Read ``folder/labels.jsonl`` (and ``dataset.json`` when present). InputFileError for a
    missing or empty label file, a line that is not a JSON object with an integer ``index`` and
    an ``image`` path, or a repeated index."""
    folder = Path(folder)
    path = folder / LABELS_FILE
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as exc:
        raise InputFileError(
            f"cannot read the dataset's labels ({exc.strerror or exc}); is {folder} a folder "
            "written by `eyelume dataset` (finished: labels.jsonl is written at the end)?",
            file=path,
        ) from None
    labels, seen = [], set()
    for n, line in enumerate(text.splitlines(), start=1):
        if line.strip():
            row = _label_line(path, n, line, seen)
            seen.add(row["index"])
            labels.append(row)
    if not labels:
        raise InputFileError("holds no label line", file=path)
    labels.sort(key=lambda r: r["index"])
    info: dict = {}
    meta = folder / "dataset.json"
    if meta.exists():
        try:
            info = json.loads(meta.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise InputFileError(f"cannot read it ({exc})", file=meta) from None
        if not isinstance(info, dict):
            raise InputFileError("is not a JSON object", file=meta)
    return DatasetFolder(folder, info, labels)


def _member(folder: Path, rel: object, what: str) -> Path:
    if not isinstance(rel, str) or not rel:
        raise InputFileError(f"'{what}' = {rel!r} is no path", file=folder / LABELS_FILE)
    return folder / rel


def _read_png(path: Path) -> np.ndarray:
    try:
        with Image.open(path) as im:
            arr = np.asarray(im)
    except (OSError, ValueError) as exc:
        raise InputFileError(f"cannot read the picture ({exc})", file=path) from None
    if arr.ndim != 2:
        raise InputFileError(f"is not a grey picture (array shape {arr.shape})", file=path)
    return arr


def read_picture(ds: DatasetFolder, label: dict) -> np.ndarray:
    """The picture of ``label`` (rows, cols) as stored: uint8 or uint16 DN."""
    return _read_png(_member(ds.folder, label["image"], "image"))


def read_segmentation(ds: DatasetFolder, label: dict, shape: tuple[int, int]) -> np.ndarray:
    """The extended segmentation (rows, cols) uint8 ids 0–7 of ``label``; InputFileError if it
    is not ``shape`` or holds another id."""
    path = _member(ds.folder, label.get("segmentation"), "segmentation")
    seg = _read_png(path)
    if seg.shape != shape:
        raise InputFileError(f"shape {seg.shape} differs from its picture's {shape}", file=path)
    if seg.max(initial=0) >= _N_CLASSES:
        raise InputFileError(f"holds class id {int(seg.max())}, not one of 0..7", file=path)
    return seg.astype(np.uint8, copy=False)


def openeds_view(seg: np.ndarray) -> np.ndarray:
    """OpenEDS' ids (0–3) from eyelume's (0–7, (rows, cols) uint8): 4 skin, 5 eyelid → 0; each
    6 glint or 7 reflection pixel → the (mapped) class of its nearest pixel that is neither
    (:func:`eyelume.analysis.labels.openeds_map` without the primary surface map: Euclidean
    distance transform; the export uses it only for a label line without the exact
    ``segmentation_openeds``, module doc). A map of glints and
    reflections only becomes 0. ValueError on a map that is not 2-D or holds another id."""
    from eyelume.analysis.labels import openeds_map

    seg = np.asarray(seg)
    if seg.ndim != 2 or (seg.size and int(seg.max()) >= _N_CLASSES):
        raise ValueError(f"a segmentation is 2-D with ids 0..7, got shape {seg.shape}")
    return openeds_map(seg)


@dataclass
class ExportSummary:
    """What :func:`export_openeds` wrote: ``out`` the root, ``split``, ``pictures``,
    ``size`` (cols, rows) or None for native, ``class_pixels`` {id: count} over all labels."""

    out: Path
    split: str
    pictures: int
    size: tuple[int, int] | None
    class_pixels: dict[int, int]


def _adc_bits(info: dict) -> int | None:
    for where in (info, info.get("sensor") if isinstance(info.get("sensor"), dict) else {}):
        bits = where.get("adc_bits")
        if isinstance(bits, int) and 8 <= bits <= 16:
            return bits
    return None


def _to_8bit(pic: np.ndarray, bits: int | None) -> tuple[np.ndarray, int]:
    if pic.dtype == np.uint8:
        return pic, 8
    if bits is None:
        bits = max(8, int(pic.max(initial=0)).bit_length())
    scaled = np.rint(pic.astype(np.float64) * (255.0 / (2**bits - 1)))
    return np.clip(scaled, 0, 255).astype(np.uint8), bits


def _fit(pic: np.ndarray, lab: np.ndarray, size: tuple[int, int]):
    """(picture, labels, scale, (offset x, offset y)) on a ``size`` (cols, rows) canvas."""
    import cv2

    rows, cols = pic.shape
    s = min(size[0] / cols, size[1] / rows)
    w, h = min(size[0], round(cols * s)), min(size[1], round(rows * s))
    if (w, h) != (cols, rows):
        how = cv2.INTER_AREA if s < 1 else cv2.INTER_LINEAR
        pic = cv2.resize(pic, (w, h), interpolation=how)
        lab = cv2.resize(lab, (w, h), interpolation=cv2.INTER_NEAREST)
    ox, oy = (size[0] - w) // 2, (size[1] - h) // 2
    canvas = np.zeros((size[1], size[0]), np.uint8)
    labels = np.zeros((size[1], size[0]), np.uint8)
    canvas[oy : oy + h, ox : ox + w] = pic
    labels[oy : oy + h, ox : ox + w] = lab
    return canvas, labels, s, (ox, oy)


def _atomic_write(path: Path, write) -> None:
    tmp = path.with_name(f".{path.name}.tmp")
    write(tmp)
    os.replace(tmp, path)


def export_openeds(
    folder: str | Path,
    out: str | Path,
    *,
    split: str = "train",
    size: tuple[int, int] | None = OPENEDS_SIZE,
    progress=None,
) -> ExportSummary:
    """Write the dataset at ``folder`` in OpenEDS' segmentation layout under ``out`` (module
    doc: ``out/split/images/NNNNNN.png``, ``out/split/labels/NNNNNN.npy``,
    ``out/eyelume_export.json``). ``size`` (cols, rows): the canvas (default OpenEDS' 640 × 400),
    or None for each picture's own size. ``progress(done, total)`` is called after each picture.
    Files are written to a temporary name and renamed: an interrupted export leaves only whole
    files. InputFileError for a folder, picture or segmentation that cannot be used;
    ValueError for a bad ``split`` or ``size``."""
    if not split or any(c in split for c in "/\\") or split in (".", ".."):
        raise ValueError(f"split must be a plain folder name, got {split!r}")
    if size is not None and (len(size) != 2 or min(size) < 1):
        raise ValueError(f"size must be (columns, rows) >= 1, got {size!r}")
    ds = read_dataset(folder)
    out = Path(out)
    images, labels_dir = out / split / "images", out / split / "labels"
    images.mkdir(parents=True, exist_ok=True)
    labels_dir.mkdir(parents=True, exist_ok=True)
    bits = _adc_bits(ds.spec)
    counts = np.zeros(4, np.int64)
    records = []
    for k, label in enumerate(ds.labels):
        pic = read_picture(ds, label)
        if "segmentation_openeds" in label:
            path = _member(ds.folder, label["segmentation_openeds"], "segmentation_openeds")
            lab = _read_png(path)
            if lab.shape != pic.shape or lab.max(initial=0) > 3:
                raise InputFileError(
                    f"an OpenEDS map must be ids 0..3 of shape {pic.shape}; got shape "
                    f"{lab.shape}, largest id {int(lab.max(initial=0))}",
                    file=path,
                )
            lab = lab.astype(np.uint8)
            how = "segmentation_openeds as written"
        else:
            lab = openeds_view(read_segmentation(ds, label, pic.shape))
            how = "openeds_view of the extended segmentation"
        pic8, used_bits = _to_8bit(pic, bits)
        if size is None:
            scale, offset = 1.0, (0, 0)
        else:
            pic8, lab, scale, offset = _fit(pic8, lab, size)
        stem = f"{label['index']:06d}"
        _atomic_write(images / f"{stem}.png", lambda p, a=pic8: Image.fromarray(a).save(p, "PNG"))
        _atomic_write(labels_dir / f"{stem}.npy", lambda p, a=lab: _save_npy(p, a))
        counts += np.bincount(lab.ravel(), minlength=4)[:4]
        records.append({
            "index": label["index"], "source_image": label["image"],
            "image": f"{split}/images/{stem}.png", "label": f"{split}/labels/{stem}.npy",
            "scale": scale, "offset_px": list(offset), "source_bits": used_bits,
            "label_from": how,
        })  # fmt: skip
        if progress is not None:
            progress(k + 1, len(ds.labels))
    manifest = {
        "format": "OpenEDS 2019 semantic segmentation layout (Garbin et al. 2019)",
        "classes": {str(k): v for k, v in OPENEDS_CLASSES.items()},
        "source": str(ds.folder),
        "dataset": ds.name,
        "scene": ds.scene,
        "seed": ds.seed,
        "split": split,
        "size_px": None if size is None else list(size),
        "pixel_mapping": "x_export = scale * (x + 0.5) - 0.5 + offset_px[0]; same for y",
        "adc_bits": bits,
        "pictures": records,
    }
    _atomic_write(
        out / "eyelume_export.json",
        lambda p: p.write_text(json.dumps(manifest, indent=1) + "\n", encoding="utf-8"),
    )
    return ExportSummary(out, split, len(records), size, {i: int(c) for i, c in enumerate(counts)})


def _save_npy(path: Path, arr: np.ndarray) -> None:
    with open(path, "wb") as f:
        np.save(f, arr)


# ------------------------------------------------------------------------------------------------
# Figures


def dataset_caption(ds: DatasetFolder) -> str:
    """``dataset NAME: scene S, seed N`` as the figures' captions say it."""
    seed = f"seed {ds.seed}" if ds.seed is not None else "seed not recorded"
    return f"dataset {ds.name}: scene {ds.scene}, {seed}"


def _sample(labels: list[dict], n: int) -> list[dict]:
    if n >= len(labels):
        return list(labels)
    picks = np.linspace(0, len(labels) - 1, n).round().astype(int)
    return [labels[i] for i in picks]


def _ellipse_patch(e: dict | None, color: str) -> Ellipse | None:
    if not isinstance(e, dict) or e.get("center_px") is None:
        return None
    (x, y), (a, b) = e["center_px"], e["semi_axes_px"]
    return Ellipse((x, y), 2 * a, 2 * b, angle=e.get("angle_deg", 0.0), fill=False,
                   edgecolor=color, linewidth=0.9)  # fmt: skip


def _panel_title(label: dict) -> str:
    gaze = label.get("gaze_deg") or {}
    pupil = label.get("pupil") or {}
    parts = [f"#{label['index']}"]
    if "horizontal" in gaze:
        parts.append(f"gaze {gaze['horizontal']:+.1f}°, {gaze.get('vertical', 0):+.1f}°")
    if isinstance(pupil.get("diameter_mm"), int | float):
        parts.append(f"pupil {pupil['diameter_mm']:.1f} mm")
    if isinstance(label.get("eye_openness"), int | float):
        parts.append(f"open {label['eye_openness']:.2f}")
    if label.get("glasses"):
        parts.append("glasses")
    return " · ".join(parts)


def _draw_labels(ax, label: dict) -> None:
    from matplotlib.transforms import offset_copy

    for key, color in (("iris", "gold"), ("pupil", "cyan")):
        patch = _ellipse_patch((label.get(key) or {}).get("ellipse"), color)
        if patch is not None:
            ax.add_patch(patch)
    pupil = ((label.get("pupil") or {}).get("ellipse") or {}).get("center_px")
    for g in label.get("glints") or []:
        p = g.get("position_px")
        if p is None:
            continue
        x, y = p
        if g.get("saturated") and g.get("visible"):
            ax.plot(x, y, marker="x", color="white", ms=5, mew=1.2)
        elif g.get("visible"):
            ax.plot(x, y, marker="o", ms=5, mfc="none", mec="red", mew=1.2)
        else:
            ax.plot(x, y, marker="o", ms=5, mfc="none", mec="0.6", mew=0.8)
        led = g.get("led")
        if isinstance(led, int) and 0 <= led < 100:
            # the LED id as a marker (not a text: ids of neighbouring glints may touch), 7 pt
            # from the glint away from the pupil's centre (image y down: points' y up)
            dx, dy = (x - pupil[0], y - pupil[1]) if pupil else (1.0, -1.0)
            norm = math.hypot(dx, dy) or 1.0
            at = offset_copy(ax.transData, fig=ax.figure, x=7 * dx / norm, y=-7 * dy / norm,
                             units="points")  # fmt: skip
            ax.plot(x, y, marker=f"${led}$", ms=6, color="red", linestyle="none", transform=at)
    for r in label.get("reflections") or []:
        p = r.get("position_px")
        if p is not None and r.get("visible", True):
            ax.plot(*p, marker="+", ms=6, color="magenta", mew=1.0)


_LEGEND = [
    Line2D([], [], color="cyan", lw=1, label="pupil ellipse"),
    Line2D([], [], color="gold", lw=1, label="iris ellipse"),
    Line2D([], [], marker="o", mfc="none", mec="red", ls="none", label="glint (LED id beside)"),
    Line2D([], [], marker="x", color="white", mec="black", ls="none", label="saturated glint"),
    Line2D([], [], marker="o", mfc="none", mec="0.6", ls="none", label="hidden / not visible"),
    Line2D([], [], marker="+", color="magenta", ls="none", label="spurious reflection"),
]


def save_contact_sheet(ds: DatasetFolder, path, *, n: int = 8, columns: int = 4) -> list[int]:
    """Draw ``n`` pictures of ``ds`` (evenly spread over its indices) with their labels (module
    doc) to ``path`` (a file or a binary buffer); return the indices drawn. One grey scale in
    DN for all (0 … 2^bits − 1 of the pictures' bit depth), one colour bar."""
    picks = _sample(ds.labels, max(1, int(n)))
    columns = max(1, min(columns, len(picks)))
    rows = math.ceil(len(picks) / columns)
    pictures = [read_picture(ds, lab) for lab in picks]
    bits = 16 if any(p.dtype == np.uint16 for p in pictures) else 8
    top = float(2**bits - 1)
    width = 2.6 * columns + 1.2
    aspect = pictures[0].shape[0] / pictures[0].shape[1]
    fig = agg_figure(width, (2.4 * aspect + 0.45) * rows + 1.2)
    axes = np.atleast_1d(fig.subplots(rows, columns, squeeze=False).ravel())
    image = None
    for ax, lab, pic in zip(axes, picks, pictures, strict=False):
        image = ax.imshow(pic, cmap=CMAP_SENSOR, vmin=0, vmax=top, interpolation="nearest")
        _draw_labels(ax, lab)
        ax.set_xlim(-0.5, pic.shape[1] - 0.5)
        ax.set_ylim(pic.shape[0] - 0.5, -0.5)
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(wrap_title(_panel_title(lab), 2.4, 7), fontsize=7)
    for ax in axes[len(picks) :]:
        ax.set_visible(False)
    bar = fig.colorbar(image, ax=list(axes[: len(picks)]), shrink=0.8)
    bar.set_label(f"digital number, {bits}-bit PNG (DN)", fontsize=8)
    bar.ax.tick_params(labelsize=7)
    fig.legend(handles=_LEGEND, loc="outside lower center", ncols=3, fontsize=7,
               facecolor="0.85")  # fmt: skip
    size = pictures[0].shape
    fig.suptitle(
        wrap_title(
            f"{len(picks)} of {len(ds.labels)} pictures ({size[1]} × {size[0]} px) with their "
            f"labels — {dataset_caption(ds)}",
            width - 0.3,
            9,
        ),
        fontsize=9,
    )
    save_figure(fig, path)
    return [lab["index"] for lab in picks]


def _unit(name: str) -> str:
    from eyelume.report.html import unit_of

    return unit_of(name) or "dimensionless"


def distribution_values(labels: list[dict]) -> dict[str, list[float]]:
    """{quantity (its unit in parentheses): values over the pictures} for the histograms:
    gaze (``gaze_deg``), pupil diameter (``pupil.diameter_mm``), each ``varied`` path (a vector
    one entry per component, ``path[x]``…) and each numeric ``person.values`` entry. Pictures
    that lack a quantity do not count for it; a quantity no picture has is left out."""
    out: dict[str, list[float]] = {}

    def add(name: str, value) -> None:
        if isinstance(value, bool) or not isinstance(value, int | float):
            return
        if math.isfinite(value):
            out.setdefault(name, []).append(float(value))

    for lab in labels:
        gaze = lab.get("gaze_deg") or {}
        add("gaze horizontal (°)", gaze.get("horizontal"))
        add("gaze vertical (°)", gaze.get("vertical"))
        add("pupil diameter (mm)", (lab.get("pupil") or {}).get("diameter_mm"))
        for path, v in sorted((lab.get("varied") or {}).items()):
            if path == "eye.pupil_diameter_mm":
                continue  # the pupil panel's
            if isinstance(v, list | tuple):
                for axis, c in zip("xyz" if len(v) == 3 else range(len(v)), v, strict=False):
                    add(f"{path}[{axis}] ({_unit(path)})", c)
            else:
                add(f"{path} ({_unit(path)})", v)
        person = lab.get("person") or {}
        for name, v in sorted((person.get("values") or {}).items()):
            add(f"person {name} ({_unit(name)})", v)
    return out


def save_distributions(ds: DatasetFolder, path, *, columns: int = 3) -> list[str]:
    """Histograms of :func:`distribution_values` and a bar of the pictures with and without
    glasses, to ``path`` (a file or a binary buffer); returns the panels' quantities."""
    values = distribution_values(ds.labels)
    names = list(values)
    panels = len(names) + 1
    columns = max(1, min(columns, panels))
    rows = math.ceil(panels / columns)
    fig = agg_figure(3.3 * columns, 2.5 * rows + 0.6)
    axes = fig.subplots(rows, columns, squeeze=False).ravel()
    for ax, name in zip(axes, names, strict=False):
        v = np.asarray(values[name])
        bins = max(5, min(30, int(math.sqrt(len(v))) + 1))
        ax.hist(v, bins=bins, color="tab:blue", edgecolor="white", linewidth=0.4)
        ax.set_xlabel(name, fontsize=8)
        ax.set_ylabel("pictures (count)", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_title(f"{len(v)} pictures, {v.min():.3g} … {v.max():.3g}", fontsize=8)
        ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax = axes[len(names)]
    with_glasses = sum(bool(lab.get("glasses")) for lab in ds.labels)
    share = with_glasses / len(ds.labels)
    ax.bar([0, 1], [len(ds.labels) - with_glasses, with_glasses], color=["0.6", "tab:orange"])
    ax.set_xticks([0, 1], ["no", "yes"])
    ax.set_xlabel("glasses (yes/no)", fontsize=8)
    ax.set_ylabel("pictures (count)", fontsize=8)
    ax.tick_params(labelsize=7)
    ax.set_title(f"glasses on {100 * share:.0f} % of the pictures", fontsize=8)
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    for ax in axes[panels:]:
        ax.set_visible(False)
    fig.suptitle(
        wrap_title(
            f"Distributions over {len(ds.labels)} pictures, read from labels.jsonl — "
            f"{dataset_caption(ds)}",
            3.3 * columns - 0.3,
            9,
        ),
        fontsize=9,
    )
    save_figure(fig, path)
    return [*names, "glasses"]


def figure_png(draw, ds: DatasetFolder, **kw) -> bytes:
    """The PNG bytes of ``draw(ds, buffer, **kw)`` (for the HTML report)."""
    buf = io.BytesIO()
    draw(ds, buf, **kw)
    return buf.getvalue()
