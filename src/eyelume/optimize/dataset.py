"""Labelled synthetic eye datasets (issue 17): a dataset file, each picture's draws and seed, the
picture made by one pure function of (dataset, index) — its labels by
:func:`eyelume.analysis.labels.picture_labels` — and the dataset run on the study's executors
and result store.

A dataset file (TOML)::

    name = "vr-offaxis-train"
    scene = "vr-offaxis"          # a preset or a scene file (relative: to the dataset file)
    seed = 1                      # the dataset's seed
    pictures = 1000
    image_bits = 8                # the PNG: 16 writes the sensor's DN as they are; 8 writes
                                  # round(DN · 255 / (2^adc_bits − 1))
    irradiance = true             # also irradiance/NNNNNN.npy (float32 W/mm², linear)
    render_noise = "sensor"       # or a relative error (0.02), or: samples_per_pixel = 4
    [gaze]                        # the fixation target (visual axis), degrees
    distribution = "uniform"      # or "normal": mean 0, sd = [h, v], truncated to the ranges
    horizontal = [-25.0, 25.0]
    vertical = [-20.0, 20.0]
    [population]                  # optional: picture i shows person (i mod size)
    size = 50
    seed = 1
    [[vary]]                      # any dotted scene path, uniform in its range per picture
    path = "eye.pupil_diameter_mm"
    range = [2.0, 7.0]
    [[vary]]
    path = "head_offset_mm"       # slip (a vector): one range per component
    range = [[-1, 1], [-1, 1], [-1, 1]]
    [glasses]                     # optional: glasses on a share of the pictures
    share = 0.3
    scene = "vr-offaxis-glasses"  # its [[elements]] are added to those pictures' scene

**Draws and seeds.** Every draw for picture i comes from its own generator,
``numpy.random.default_rng([seed, i, TAG])`` with one tag per purpose (gaze, glasses, each
[[vary]] in its order), and its render and sensor noise from :func:`picture_seed` (seed, i):
picture i depends on (the dataset file, the scenes, i) only — never on how many pictures,
workers or batches there are — so :func:`make_picture` re-renders any one alone, bit for bit.

**The picture's scene**: the base scene; with glasses, the glasses scene's ``[[elements]]``
appended; the person's overrides (:mod:`eyelume.scene.population`, person i mod size); the
[[vary]] values (a [[vary]] path wins over the person's value for the same path); then the
gaze: the eye turned so that its visual axis has the drawn angles
(:func:`eyelume.analysis.truth.optical_gaze_for`). When that needs an optical gaze beyond the
eye's ±30° (a large kappa), the optical gaze is clipped to ±30° and the label reports the
visual axis the eye then has.

**The render budget.** ``render_noise = "sensor"`` (the default) keeps the render's own noise
— the median skin pixel's relative standard error, as :func:`eyelume.render.render` measures it
with ``rel_error`` — below the sensor's shot noise there, 1/sqrt(N̄) for the N̄ mean
photo-electrons of the median skin pixel (:func:`eyelume.detectors.sensor.electrons_per_w_mm2`).
N̄ is not known before the picture is rendered, so a pilot render finds it
(:func:`eyelume.optimize.render_budget.sensor_noise_target`, shared with tracking
evaluation): the same scene sampled by a coarse grid of :data:`PILOT_COLS`
columns over the same field (irradiance is per unit area, so a coarse pixel reads the mean of
the fine ones under it; the median over the skin's few hundred coarse pixels is within a per
cent or so), :data:`PILOT_SAMPLES` samples per pixel, its own seed; the target is
:data:`SENSOR_NOISE_MARGIN` / sqrt(N̄) (the margin absorbs the pilot's estimate). Its cost is
a few per cent of the picture's on vr-offaxis. The label's ``render`` says what was reached:
``median_skin_rel_error`` of the delivered picture against ``skin_shot_noise`` computed from
that picture's own median skin pixel. A number is a fixed rel_error target;
``samples_per_pixel`` a fixed budget. The fast estimator renders every picture.

**The folder** (``/work/dataset_spec.md``, README): ``dataset.json``, ``results.sqlite`` (the
study's :class:`~eyelume.optimize.store.ResultStore`: one row per picture, the label as its
metrics), ``labels.jsonl`` (rewritten from the store, sorted by index, when a run ends or is
interrupted), ``schema.json`` (the label lines' JSON schema), ``images/``, ``irradiance/``,
``segmentation/`` (the class ids of :mod:`eyelume.analysis.labels`), ``segmentation_openeds/``
(OpenEDS' ids 0–3, exact under the glints: what ``eyelume dataset-export`` copies). A
worker writes a picture's files (each to a temporary name, then renamed) and returns its
label; the parent commits it: a picture is done when its label is in the store, and
``resume`` renders the others again, overwriting their files with the same bytes.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import Field, field_validator, model_validator

from eyelume.errors import EyelumeError, GeometryError, SceneError, StoreError
from eyelume.json_files import dumps, write_json
from eyelume.optimize.render_budget import (  # noqa: F401 - the dataset's budget names
    NO_EYE_PLANE,
    PILOT_COLS,
    PILOT_SAMPLES,
    SENSOR_NOISE_MARGIN,
    noise_options,
    sensor_noise_target,
)
from eyelume.optimize.study import beside, read_input_file
from eyelume.scene.io import apply_overrides, load_scene, not_a_path
from eyelume.scene.model import Scene
from eyelume.scene.model import _Model as _Table  # extra keys, NaN and true-for-a-number refused
from eyelume.scene.population import Person, Population, sample_people

__all__ = [
    "DATASET_FILE",
    "LABELS_FILE",
    "Dataset",
    "Picture",
    "PicturePlan",
    "check_out",
    "load_dataset",
    "make_picture",
    "picture_seed",
    "plan_picture",
    "refuse_not_empty",
    "run_dataset",
    "sensor_noise_target",
    "write_labels",
]

#: The resolved dataset file, the eyelume version and the scenes' hashes, in the folder.
DATASET_FILE = "dataset.json"
#: One label per line, sorted by index (rewritten from the store when a run ends).
LABELS_FILE = "labels.jsonl"
#: The label lines' JSON schema (a copy of eyelume/analysis/dataset_label.schema.json).
SCHEMA_FILE = "schema.json"
#: Most pictures a dataset may plan (a typo guard: 10⁷ pictures are months of this machine).
MAX_PICTURES = 10_000_000
#: Digits of a picture's file name (more when the dataset has more pictures).
INDEX_DIGITS = 6
#: The eye's range of optical gaze (degrees): compile refuses beyond it.
GAZE_LIMIT_DEG = 30.0

#: The third word of each per-picture generator's seed (module docstring): one stream per use.
_SEED_TAG = 0xDA7A5EED
_GAZE_TAG = 0x6A2E
_GLASSES_TAG = 0x6_1A55
_VARY_TAG = 0x7A_12E5


# --- the dataset file ---------------------------------------------------------------------------


class Gaze(_Table):
    """The fixation targets (the visual axis's angles, degrees): ``uniform`` over the ranges,
    or ``normal`` with mean 0 and standard deviations ``sd`` = [h, v], truncated to them."""

    distribution: Literal["uniform", "normal"] = "uniform"
    horizontal: tuple[float, float] = (-25.0, 25.0)
    vertical: tuple[float, float] = (-20.0, 20.0)
    sd: tuple[float, float] | None = None

    @model_validator(mode="after")
    def _ranges(self) -> Gaze:
        for name in ("horizontal", "vertical"):
            lo, hi = getattr(self, name)
            if not -GAZE_LIMIT_DEG <= lo <= hi <= GAZE_LIMIT_DEG:
                raise ValueError(
                    f"gaze.{name} = {[lo, hi]}: must be [low, high] with low ≤ high within the "
                    f"eye's ±{GAZE_LIMIT_DEG:g}°"
                )
        if self.distribution == "normal" and (self.sd is None or min(self.sd) <= 0):
            raise ValueError(f"gaze.sd = {self.sd}: a normal gaze needs sd = [h, v] > 0 degrees")
        if self.distribution == "uniform" and self.sd is not None:
            raise ValueError("gaze.sd is for distribution = 'normal'")
        return self


class DatasetVary(_Table):
    """One varied scene path, uniform per picture in ``range`` = [low, high] (a vector path:
    one [low, high] per component)."""

    path: str
    range: tuple[float, float] | list[tuple[float, float]]

    @model_validator(mode="after")
    def _ordered(self) -> DatasetVary:
        pairs = [self.range] if isinstance(self.range, tuple) else self.range
        if not pairs:
            raise ValueError(f"vary '{self.path}': range is empty")
        for lo, hi in pairs:
            if lo > hi:
                raise ValueError(f"vary '{self.path}': range {[lo, hi]} has low > high")
        if self.path.startswith("eye.gaze_"):
            raise ValueError(f"vary '{self.path}': the gaze is drawn by the [gaze] table")
        return self

    def draw(self, u: np.ndarray) -> float | list[float]:
        """The value for uniform deviates ``u`` (one per component)."""
        if isinstance(self.range, tuple):
            lo, hi = self.range
            return float(lo + u[0] * (hi - lo))
        return [float(lo + x * (hi - lo)) for (lo, hi), x in zip(self.range, u, strict=True)]

    @property
    def components(self) -> int:
        return 1 if isinstance(self.range, tuple) else len(self.range)

    def ends(self) -> tuple:
        """(all lows, all highs) as values of the path."""
        if isinstance(self.range, tuple):
            return self.range
        return [lo for lo, _ in self.range], [hi for _, hi in self.range]


class Glasses(_Table):
    """Glasses on a ``share`` of the pictures: ``scene``'s ``[[elements]]`` added to theirs."""

    share: float = Field(ge=0.0, le=1.0)
    scene: str = "vr-offaxis-glasses"


class Dataset(_Table):
    """A dataset file (module docstring)."""

    name: str = Field(min_length=1)
    scene: str = "vr-offaxis"
    seed: int = Field(0, ge=0, lt=2**63)
    pictures: int = Field(ge=1, le=MAX_PICTURES)
    image_bits: Literal[8, 16] = 8
    irradiance: bool = True
    render_noise: Literal["sensor"] | float | None = None
    samples_per_pixel: int | None = Field(None, ge=1, le=65536)
    max_samples_per_pixel: int = Field(4096, ge=1, le=1 << 20)
    gaze: Gaze = Gaze()
    population: Population | None = None
    vary: list[DatasetVary] = []
    glasses: Glasses | None = None

    @field_validator("render_noise")
    @classmethod
    def _relative_error(cls, value):
        """A relative error in (0, 1): an error of the field itself, so its one line names
        ``render_noise`` and the value given."""
        if isinstance(value, float) and not 0.0 < value < 1.0:
            raise ValueError("must be 'sensor' or a relative error in (0, 1), e.g. 0.02")
        return value

    @model_validator(mode="after")
    def _budget(self) -> Dataset:
        if self.samples_per_pixel is not None and self.render_noise is not None:
            raise ValueError("give render_noise or samples_per_pixel, not both")
        return self

    @property
    def noise(self) -> str | float | None:
        """The render budget: "sensor" (the default), a relative error, or None for a fixed
        ``samples_per_pixel``."""
        if self.samples_per_pixel is not None:
            return None
        return "sensor" if self.render_noise is None else self.render_noise

    @property
    def index_digits(self) -> int:
        return max(INDEX_DIGITS, len(str(self.pictures - 1)))


def load_dataset(path: str | Path) -> Dataset:
    """Read and check a dataset file before anything is written: the base and glasses scenes
    load (a relative path is the dataset file's neighbour), the glasses scene has optical
    elements and the base scene takes them, every [[vary]] path takes both ends of its range
    (alone and together), the population's first person exists, the sensor's QE covers the
    LEDs. SceneError, one line naming the dataset file, the field and the value."""
    p = Path(path)
    ds = read_input_file(p, "dataset", Dataset)
    where = f"dataset {p}"
    update = {"scene": beside(p, ds.scene)}
    if ds.glasses is not None:
        update["glasses"] = ds.glasses.model_copy(update={"scene": beside(p, ds.glasses.scene)})
    ds = ds.model_copy(update=update)
    try:
        base = load_scene(ds.scene)
    except EyelumeError as exc:
        raise SceneError(f"{where}: field 'scene': {exc}") from None
    _check_vary(ds, base, where)
    if ds.population is not None:
        try:
            sample_people(base, 1, ds.population.seed, ds.population)
        except EyelumeError as exc:
            raise SceneError(f"{where}: field 'population': {exc}") from None
    _check_scenes(ds, base, where)
    return ds


def _check_vary(ds: Dataset, base: Scene, where: str) -> None:
    """Each [[vary]] path with both ends of its range, then all lows and all highs together."""
    for i, v in enumerate(ds.vary):
        for value in v.ends():
            try:
                apply_overrides(base, {v.path: value})
            except EyelumeError as exc:
                if not_a_path(exc, v.path):
                    raise SceneError(
                        "not a field of the scene (a dotted path such as eye.pupil_diameter_mm)",
                        file=where, field=f"vary[{i}].path", value=v.path,
                    ) from None  # fmt: skip
                raise SceneError(
                    exc.message if exc.field else str(exc),
                    file=where,
                    field=f"vary[{i}].range ({v.path})",
                    value=value,
                ) from None
    for end in (0, 1):
        values = {v.path: v.ends()[end] for v in ds.vary}
        try:
            apply_overrides(base, values)
        except EyelumeError as exc:
            which = "lows" if end == 0 else "highs"
            raise SceneError(f"{where}: the [[vary]] {which} together: {exc}") from None


def _check_scenes(ds: Dataset, base: Scene, where: str) -> None:
    """The base scene (and with glasses, glasses on it) compiled for the fast estimator, with
    skin in the picture when the render budget is measured there."""
    from eyelume.analysis.regions import region_masks
    from eyelume.compile import compile_scene
    from eyelume.render import check_estimator, check_sensor_spectra

    scenes = [("scene", base)]
    if ds.glasses is not None:
        try:
            glasses = load_scene(ds.glasses.scene)
        except EyelumeError as exc:
            raise SceneError(f"{where}: field 'glasses.scene': {exc}") from None
        if not glasses.elements:
            raise SceneError(
                "has no [[elements]] to add", file=where, field="glasses.scene",
                value=ds.glasses.scene,
            )  # fmt: skip
        try:
            scenes.append(("glasses.scene", with_glasses(base, glasses)))
        except EyelumeError as exc:
            raise SceneError(f"{where}: field 'glasses.scene': {exc}") from None
    for field, sc in scenes:
        try:
            check_sensor_spectra(sc)
            cs = compile_scene(sc)
            check_estimator(sc, "fast", cs, command="dataset")
        except EyelumeError as exc:
            raise SceneError(f"{where}: field '{field}': {exc}") from None
    if ds.samples_per_pixel is None and not region_masks(cs, reflections=False)["skin"].any():
        raise SceneError(
            "the picture shows no skin, where the render's noise is measured: give "
            "samples_per_pixel instead",
            file=where,
            field="render_noise",
            value=ds.noise,
        )


def with_glasses(base: Scene, glasses: Scene) -> Scene:
    """``base`` with ``glasses``'s optical elements added after its own."""
    elements = [e.model_dump(mode="python") for e in (*base.elements, *glasses.elements)]
    return apply_overrides(base, {"elements": elements})


# --- one picture's draws --------------------------------------------------------------------------


def picture_seed(seed: int, index: int) -> int:
    """The seed of picture ``index``'s render and sensor noise in a dataset of ``seed``: the first
    63 bits of ``numpy.random.SeedSequence([seed, index, 0xDA7A5EED])``'s first 64-bit word.

    >>> picture_seed(1, 7) == picture_seed(1, 7) != picture_seed(1, 8)
    True
    """
    state = np.random.SeedSequence([int(seed), int(index), _SEED_TAG])
    return int(state.generate_state(1, dtype=np.uint64)[0] >> np.uint64(1))


@dataclass(frozen=True)
class PicturePlan:
    """What picture ``index`` shows: its ``seed`` (:func:`picture_seed`), the fixation target
    ``gaze_deg`` (h, v) of the visual axis, ``glasses``, the [[vary]] values ``varied`` (path →
    value) and the ``person``'s index in the population (None without one)."""

    index: int
    seed: int
    gaze_deg: tuple[float, float]
    glasses: bool
    varied: dict
    person: int | None


def _rng(ds: Dataset, index: int, *tag: int) -> np.random.Generator:
    return np.random.default_rng([ds.seed, index, *tag])


def _draw_gaze(gaze: Gaze, u: np.ndarray) -> tuple[float, float]:
    if gaze.distribution == "uniform":
        return tuple(
            float(lo + x * (hi - lo))
            for (lo, hi), x in zip((gaze.horizontal, gaze.vertical), u, strict=True)
        )
    from scipy.stats import truncnorm

    out = []
    for (lo, hi), sd, x in zip((gaze.horizontal, gaze.vertical), gaze.sd, u, strict=True):
        out.append(float(lo) if lo == hi else float(truncnorm.ppf(x, lo / sd, hi / sd, scale=sd)))
    return out[0], out[1]


def plan_picture(ds: Dataset, index: int) -> PicturePlan:
    """Picture ``index``'s draws (module docstring: each from its own generator)."""
    if not 0 <= index < ds.pictures:
        raise ValueError(f"picture {index}: the dataset has pictures 0 to {ds.pictures - 1}")
    gaze = _draw_gaze(ds.gaze, _rng(ds, index, _GAZE_TAG).random(2))
    glasses = ds.glasses is not None and bool(
        _rng(ds, index, _GLASSES_TAG).random() < ds.glasses.share
    )
    varied = {
        v.path: v.draw(_rng(ds, index, _VARY_TAG, k).random(v.components))
        for k, v in enumerate(ds.vary)
    }
    person = None if ds.population is None else index % ds.population.size
    return PicturePlan(index, picture_seed(ds.seed, index), gaze, glasses, varied, person)


# --- one picture --------------------------------------------------------------------------------


class _Bases:
    """A dataset's scenes, resolved once per process: the base, the base with glasses, and
    its people as they are asked for."""

    def __init__(self, ds: Dataset, base: Scene, glasses: Scene | None) -> None:
        self.ds, self.base = ds, base
        self.with_glasses = None if glasses is None else with_glasses(base, glasses)
        self.glasses = glasses

    @lru_cache(maxsize=256)  # noqa: B019 - one _Bases per dataset per process (_bases)
    def person(self, j: int) -> Person:
        pop = self.ds.population
        return sample_people(self.base, 1, pop.seed, pop, start=j, build_scenes=False)[0]

    def context(self) -> str:
        """The JSON a worker rebuilds this from (:func:`_bases_from`): no file is read there."""
        return json.dumps(
            {
                "dataset": self.ds.model_dump(mode="json"),
                "scene": self.base.model_dump(mode="json"),
                "glasses": None if self.glasses is None else self.glasses.model_dump(mode="json"),
            },
            sort_keys=True,
        )

    def key_prefix(self) -> str:
        """SHA-256 of everything a picture depends on besides its index: the dataset file
        without its name and picture count, and the scenes' contents (not their paths)."""
        ds = self.ds.model_dump(mode="json")
        for k in ("name", "pictures", "scene"):
            ds.pop(k)
        if ds.get("glasses"):
            ds["glasses"].pop("scene")
        payload = {
            "dataset": ds,
            "scene": self.base.model_dump(mode="json"),
            "glasses": None if self.glasses is None else self.glasses.model_dump(mode="json"),
        }
        return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()


def bases(ds: Dataset) -> _Bases:
    """A dataset's scenes loaded from its files (:func:`load_dataset` checked them)."""
    glasses = None if ds.glasses is None else load_scene(ds.glasses.scene)
    return _Bases(ds, load_scene(ds.scene), glasses)


@lru_cache(maxsize=4)
def _bases_from(context: str) -> _Bases:
    data = json.loads(context)
    glasses = None if data["glasses"] is None else Scene.model_validate(data["glasses"])
    return _Bases(
        Dataset.model_validate(data["dataset"]), Scene.model_validate(data["scene"]), glasses
    )


def picture_scene(b: _Bases, plan: PicturePlan) -> tuple[Scene, dict | None]:
    """(the scene of the picture, its person entry for the label) (module docstring)."""
    from eyelume.analysis.truth import optical_gaze_for

    base = b.with_glasses if plan.glasses else b.base
    over: dict = {}
    entry = None
    if plan.person is not None:
        person = b.person(plan.person)
        over.update(person.overrides)
        entry = {"index": person.index, "values": person.values}
    over.update(plan.varied)
    sc = apply_overrides(base, over) if over else base
    h, v = plan.gaze_deg
    try:
        gh, gv = optical_gaze_for(sc, h, v)
    except GeometryError:  # beyond the eye's range: the optical gaze clipped (module docstring)
        kh, kv = sc.eye.kappa_deg
        gh = float(np.clip(h - kh, -GAZE_LIMIT_DEG, GAZE_LIMIT_DEG))
        gv = float(np.clip(v - kv, -GAZE_LIMIT_DEG, GAZE_LIMIT_DEG))
    gaze = {"eye.gaze_horizontal_deg": gh, "eye.gaze_vertical_deg": gv}
    return apply_overrides(sc, {**gaze, **_NO_EYE_PLANE}), entry


#: A picture's scene has an eye-plane receiver of one bin (:data:`~eyelume.optimize.
#: render_budget.NO_EYE_PLANE`): no label uses the eye plane.
_NO_EYE_PLANE = NO_EYE_PLANE


@dataclass
class Picture:
    """One picture of a dataset (:func:`make_picture`): its ``plan``, ``scene``, the digital
    picture ``counts`` ((rows, cols) uint16 DN), the ``image`` written to the PNG (uint8 or
    uint16), the ``irradiance`` ((rows, cols) float32 W/mm² at the scene's wavelength), the
    ``segmentation`` ((rows, cols) uint8 class ids, :data:`eyelume.analysis.labels.
    SEGMENTATION_CLASSES`), the ``label`` (one line of labels.jsonl: the bookkeeping keys
    and :func:`eyelume.analysis.labels.picture_labels`' labels) and ``openeds`` ((rows, cols)
    uint8 OpenEDS ids 0–3, exact: the class under each glint and reflection pixel from the
    scene's primary surface map, :func:`eyelume.analysis.labels.openeds_map`)."""

    plan: PicturePlan
    scene: Scene
    counts: np.ndarray
    image: np.ndarray
    irradiance: np.ndarray
    segmentation: np.ndarray
    label: dict
    openeds: np.ndarray | None = None


def _render_options(ds: Dataset, sc: Scene, seed: int):
    """(RenderOptions, the budget's facts for the label): a fixed ``samples_per_pixel``, or the
    targets and facts of :func:`eyelume.optimize.render_budget.noise_options` (the rule tracking
    uses: with sunlight the LEDs' and the sun's renders each to their own shot noise)."""
    from eyelume.render import RenderOptions

    if ds.samples_per_pixel is not None:
        opts = RenderOptions(estimator="fast", samples_per_pixel=ds.samples_per_pixel, seed=seed)
        return opts, {"budget": "samples_per_pixel"}
    target, facts = noise_options(sc, ds.noise, seed, ds.max_samples_per_pixel)
    opts = RenderOptions(
        estimator="fast", rel_error=target, max_samples_per_pixel=ds.max_samples_per_pixel,
        seed=seed, ambient_rel_error=facts.get("ambient_target_rel_error"),
    )  # fmt: skip
    return opts, facts


def _file(ds: Dataset, folder: str, index: int, ext: str) -> str:
    return f"{folder}/{index:0{ds.index_digits}d}.{ext}"


def make_picture(ds: Dataset, index: int, b: _Bases | None = None) -> Picture:
    """Picture ``index`` of ``ds``: its scene, rendered (fast estimator, the dataset's budget),
    read out by the sensor (:func:`eyelume.detectors.sensor.digitize` with the picture's seed),
    its truth and label. A pure function of (``ds``, ``index``): the same arrays and label in
    any process, alone or in a run of any number of workers.

    Raises KeyboardInterrupt when Ctrl-C or SIGTERM cut its render short (a partial picture is
    never a picture of the dataset)."""
    from eyelume.analysis.labels import picture_labels
    from eyelume.analysis.truth import eye_truth
    from eyelume.compile import compile_scene
    from eyelume.detectors.sensor import digitize, electrons_per_w_mm2
    from eyelume.render import render

    b = b or bases(ds)
    plan = plan_picture(ds, index)
    sc, person = picture_scene(b, plan)
    cs = compile_scene(sc)
    opts, budget = _render_options(ds, sc, plan.seed)
    result = render(cs, opts)
    if result.interrupted:
        raise KeyboardInterrupt
    irradiance = result.eye_image_at_scene_wavelength
    digital = digitize(irradiance, sc.sensor, sc.wavelength_nm, plan.seed)
    full = digital.full_scale_dn
    if ds.image_bits == 16:
        image = digital.counts
    else:
        image = np.rint(digital.counts.astype(np.float64) * (255.0 / full)).astype(np.uint8)
    skin = result.region_stats()["skin"]
    shot = None
    if skin.get("pixels"):
        n_e = skin["median_w_mm2"] * electrons_per_w_mm2(sc.sensor, float(sc.wavelength_nm))
        shot = 1.0 / math.sqrt(n_e) if n_e > 0 else None
    truth = eye_truth(cs)
    labels, segmentation, openeds = picture_labels(
        cs, digital.counts, digital.saturated, irradiance, result.regions, truth, openeds=True
    )
    label = {
        "index": index,
        "seed": plan.seed,
        "image": _file(ds, "images", index, "png"),
        "irradiance": _file(ds, "irradiance", index, "npy") if ds.irradiance else None,
        "segmentation": _file(ds, "segmentation", index, "png"),
        "segmentation_openeds": _file(ds, "segmentation_openeds", index, "png"),
        "image_bits": ds.image_bits,
        "varied": plan.varied,
        "person": person,
        "glasses": plan.glasses,
        **labels,
        "render": {
            "estimator": "fast",
            "samples_per_pixel": result.samples_per_pixel,
            "median_skin_rel_error": skin.get("median_pixel_rel_error"),
            "skin_shot_noise": shot,
            **budget,
        },
    }
    return Picture(
        plan, sc, digital.counts, image, irradiance.astype(np.float32), segmentation, label,
        openeds,
    )  # fmt: skip


# --- files ------------------------------------------------------------------------------------


def _write_atomic(path: Path, data: bytes) -> None:
    """``data`` to ``path`` through a temporary name in the same folder and a rename: a reader
    (or a run killed mid-write) sees the old file or the new one, never half of one."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_bytes(data)
    os.replace(tmp, path)


def _png(image: np.ndarray) -> bytes:
    import cv2

    ok, buf = cv2.imencode(".png", np.ascontiguousarray(image))
    if not ok:  # pragma: no cover - OpenCV encodes any uint8/uint16 2-D array
        raise OSError("OpenCV could not encode the PNG")
    return buf.tobytes()


def write_picture(pic: Picture, out: Path) -> None:
    """The picture's files in ``out`` (the label names them), each written atomically."""
    label = pic.label
    _write_atomic(out / label["image"], _png(pic.image))
    _write_atomic(out / label["segmentation"], _png(pic.segmentation))
    if pic.openeds is not None:
        _write_atomic(out / label["segmentation_openeds"], _png(pic.openeds))
    if label["irradiance"] is not None:
        buf = io.BytesIO()
        np.save(buf, pic.irradiance)
        _write_atomic(out / label["irradiance"], buf.getvalue())


def _picture_task(context: str, out: str, index: int) -> tuple[dict, float]:
    """A worker's task: picture ``index`` made and its files written; (label, seconds)."""
    t0 = time.perf_counter()
    b = _bases_from(context)
    try:
        pic = make_picture(b.ds, index, b)
    except EyelumeError as exc:  # a scene the draws make that cannot exist: say which picture
        plan = plan_picture(b.ds, index)
        drawn = ", ".join(f"{k} = {v!r}" for k, v in plan.varied.items())
        raise SceneError(
            f"picture {index} (gaze {list(plan.gaze_deg)}, person {plan.person}, glasses "
            f"{plan.glasses}{', ' + drawn if drawn else ''}): {exc}"
        ) from None
    write_picture(pic, Path(out))
    return pic.label, time.perf_counter() - t0


# --- the run ------------------------------------------------------------------------------------


def _folders(ds: Dataset) -> list[str]:
    return ["images", "segmentation", "segmentation_openeds",
            *(["irradiance"] if ds.irradiance else [])]  # fmt: skip


def _prepare(ds: Dataset, b: _Bases, out: Path, resume: bool) -> None:
    """Refuse a folder that is not this dataset's to continue; write dataset.json; make the
    picture folders and drop temporary files a killed run left."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        __version__ = version("eyelume")
    except PackageNotFoundError:  # run from a source tree that was never installed
        __version__ = "unknown"
    prefix = b.key_prefix()
    record = {
        "dataset": ds.model_dump(mode="json"),
        "eyelume_version": __version__,
        "scene_json_sha256": _sha(b.base),
        "glasses_scene_json_sha256": None if b.glasses is None else _sha(b.glasses),
        "picture_key_sha256": prefix,
        "adc_bits": b.base.sensor.adc_bits,
    }
    _refuse_another(ds, b, out)
    write_json(out / DATASET_FILE, record)
    schema = resources.files("eyelume.analysis") / "dataset_label.schema.json"
    _write_atomic(out / SCHEMA_FILE, schema.read_bytes())
    for folder in _folders(ds):
        (out / folder).mkdir(exist_ok=True)
        for stale in (out / folder).glob(".*.tmp"):
            stale.unlink(missing_ok=True)


def _refuse_another(ds: Dataset, b: _Bases, out: Path) -> None:
    """StoreError when ``out`` holds a dataset.json of another dataset file or scene (its
    picture key differs: :meth:`_Bases.key_prefix`), naming the fields that differ."""
    old_path = out / DATASET_FILE
    if not old_path.is_file():
        return
    try:
        old = json.loads(old_path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        old = {}
    if not isinstance(old, dict) or old.get("picture_key_sha256") != b.key_prefix():
        differ = _differences((old or {}).get("dataset") or {}, ds.model_dump(mode="json"))
        raise StoreError(
            f"holds pictures of another dataset file or scene ({DATASET_FILE} {differ}); "
            "use a new --out",
            file=out,
        )
    before = ((old or {}).get("dataset") or {}).get("pictures")
    if isinstance(before, int) and ds.pictures < before:
        # the store keeps the finished pictures, but labels.jsonl and dataset.json would be
        # rewritten for the first ds.pictures only, the files beyond them left unlabelled
        raise StoreError(
            f"was made for pictures = {before}; pictures = {ds.pictures} would leave "
            f"{before - ds.pictures} of them unlabelled (--resume only adds pictures): "
            "use a new --out",
            file=out,
        )


def check_out(ds: Dataset, out: str | Path, resume: bool, b: _Bases | None = None) -> None:
    """The checks of ``out`` that need no picture, made before any render (the command line
    makes them before its opening line): without ``resume`` a folder that is not empty
    (:func:`refuse_not_empty`); with it, a folder of another dataset file or scene, or of the
    same one made for more pictures than ``ds.pictures``. StoreError in one line."""
    out = Path(out)
    refuse_not_empty(out, resume)
    _refuse_another(ds, b or bases(ds), out)


def _sha(scene: Scene) -> str:
    text = json.dumps(scene.model_dump(mode="json"), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _differences(old: dict, new: dict) -> str:
    keys = [k for k in sorted(set(old) | set(new)) if k != "pictures" and old.get(k) != new.get(k)]
    return "differs in " + ", ".join(keys) if keys else "its scenes differ"


def refuse_not_empty(out: Path, resume: bool) -> None:
    """Without ``resume``, StoreError for a folder ``out`` that exists and holds anything (as
    ``eyelume study`` refuses a folder with runs): a dataset is made into a new or empty
    folder, or continued with ``resume``."""
    out = Path(out)
    if resume or not out.is_dir():
        return
    entries = sorted(p.name for p in out.iterdir())
    if entries:
        raise StoreError(
            f"{out}: not empty ({', '.join(entries[:3])}{', …' if len(entries) > 3 else ''}); "
            "use --resume to continue a dataset there, or a new --out"
        )


def picture_key(prefix: str, index: int) -> str:
    """The store key of picture ``index`` (a dataset's :meth:`_Bases.key_prefix` and it)."""
    return f"{prefix}:{index}"


def write_labels(store, ds: Dataset, prefix: str, out: Path) -> int:
    """labels.jsonl rewritten from the store: the labels of this dataset's finished pictures,
    sorted by index, one JSON object a line, streamed (never all in memory), written to a
    temporary file and renamed. Returns the lines written."""
    path = out / LABELS_FILE
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    n = 0
    with open(tmp, "w", encoding="utf-8") as f:
        for row in store.each_row():
            i = row["index"]
            if i < ds.pictures and row["key"] == picture_key(prefix, i):
                f.write(dumps(row["metrics"], indent=None) + "\n")
                n += 1
    os.replace(tmp, path)
    return n


def run_dataset(
    ds: Dataset,
    out: str | Path,
    workers: int | None = None,
    resume: bool = False,
    progress: Callable[[int, int], None] | None = None,
    dask: str | None = None,
    lock_timeout_s: float | None = None,
    note: Callable[[str], None] | None = None,
) -> int:
    """Make every picture of ``ds`` not yet in ``out``'s store; returns how many are done.

    The pictures run on the study's executors (:func:`eyelume.optimize.runner.run_tasks`: a
    local pool of ``workers`` processes, or Dask), each worker writing its picture's files,
    this process committing each label to the store (:class:`~eyelume.optimize.store.
    ResultStore`) as it arrives; labels.jsonl is rewritten from the store at the end, also when
    the run is interrupted. Without ``resume``, a folder that is not empty is refused
    (StoreError); with it, the finished pictures are skipped — the folder must hold this same
    dataset (the file but its name and picture count, and the scenes). ``progress(done,
    total)`` after each commit; ``note(message)`` when a commit waits for another program's
    write lock. KeyboardInterrupt (Ctrl-C, SIGTERM via the command line) stops the workers at
    once and is raised after labels.jsonl is written; what is committed stays."""
    from eyelume.optimize.runner import run_tasks
    from eyelume.optimize.store import LOCK_TIMEOUT_S, ResultStore

    out = Path(out)
    b = bases(ds)
    prefix = b.key_prefix()
    check_out(ds, out, resume, b)
    store = ResultStore(out, LOCK_TIMEOUT_S if lock_timeout_s is None else lock_timeout_s)
    store.on_wait = note
    try:
        others = store.studies() - {ds.name}
        if others:
            raise StoreError(f"{out}: holds pictures of another dataset ({', '.join(others)})")
        _prepare(ds, b, out, resume)
        finished = store.count(below=ds.pictures)
        if progress:
            progress(finished, ds.pictures)
        context = b.context()

        def tasks():
            for i in range(ds.pictures):
                key = picture_key(prefix, i)
                if not store.has(key):
                    yield (i, key), (context, str(out), i)

        def commit(tag: tuple[int, str], result: tuple[dict, float]) -> None:
            nonlocal finished
            label, seconds = result
            store.put(tag[1], tag[0], ds.name, label["varied"], label, seconds)
            finished += 1
            if progress:
                progress(finished, ds.pictures)

        try:
            run_tasks(_picture_task, tasks(), commit, workers, dask)
        except KeyboardInterrupt:
            write_labels(store, ds, prefix, out)
            raise
        return write_labels(store, ds, prefix, out)
    finally:
        store.close()
