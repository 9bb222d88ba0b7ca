"""A study: one base scene, parameters varied by their dotted scene paths, metrics per run.

A study file (TOML)::

    name = "led-height"
    scene = "paper2005"            # a preset or a scene file (relative: to the study file)
    seed = 1                       # for random and Latin-hypercube samples, and every render
    metrics = ["eye_plane_merit", "eye_image_merit", "skin_uniformity", "tracking", "safety",
               "glints"]
    delta = 0.3                    # the eye-plane target of eye_plane_merit
    samples_per_pixel = 16         # renders of eye_image_merit / skin_uniformity
    # glints: glints_visible_min / _mean over a ±20° × ±15° gaze grid and the share of gazes
    # with every LED's glint on the cornea and seen (eyelume.analysis.truth.glint_counts)
    # ghosts (optical elements): false glints (element ghosts a detector would take for glints)
    # over the same grid from the truth: their mean and max count per gaze and their smallest
    # distance (px) to a true glint and to the pupil's centre
    # (eyelume.analysis.ghosts.false_glint_counts)

    [[vary]]                       # one table per parameter; the runs are their product
    path = "leds.height_mm"
    grid = [20.0, 40.0, 5]         # start, stop, count (inclusive)
    [[vary]]
    path = "leds.pitch_deg"
    values = [0, 10, 20, 30]       # an explicit list
    [[vary]]
    path = "leds.distance_mm"
    random = [40.0, 70.0]          # uniform in a range ...
    samples = 4                    # ... this many draws (seed)
    # latin = [lo, hi] with samples: a Latin hypercube over all `latin` parameters together

    [population]                   # optional: N people (eyelume.scene.population.Population):
    size = 50                      # the "tracking" metric (required with it) is then evaluated
    seed = 1                       # over them on each run's design (run_metrics)

Each run is one dict of overrides; its key is the SHA-256 of the base scene's JSON, the
overrides, the metrics and their settings, so a changed input is a new run and an unchanged one
is found in the store (:mod:`.store`) and not run again.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import tomllib
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import Field, ValidationError, model_validator

from eyelume.errors import EyelumeError
from eyelume.scene.io import (
    SceneError,
    apply_overrides,
    load_scene,
    not_a_path,
    preset_names,
    validation_error,
)
from eyelume.scene.model import Scene
from eyelume.scene.model import _Model as _Table  # extra keys, NaN and true-for-a-number refused
from eyelume.scene.population import Population, sample_people
from eyelume.scene.textfile import decode_text

__all__ = [
    "METRICS",
    "Study",
    "Vary",
    "load_study",
    "plan_runs",
    "population_metrics",
    "run_count",
    "run_key",
    "run_metrics",
]

METRICS = (
    "eye_plane_merit",
    "eye_image_merit",
    "skin_uniformity",
    "tracking",
    "safety",
    "glints",
    "ghosts",
)


class Vary(_Table):
    """One varied parameter: exactly one of grid, values, random, latin (finite numbers; the
    values may be true/false for a switch such as ``camera.body.enabled``)."""

    path: str
    grid: tuple[float, float, int] | None = None
    values: list[bool | int | float | str] | None = None
    random: tuple[float, float] | None = None
    latin: tuple[float, float] | None = None
    samples: int = Field(0, ge=0)

    @model_validator(mode="after")
    def _one_kind(self) -> Vary:
        kinds = [k for k in ("grid", "values", "random", "latin") if getattr(self, k) is not None]
        if len(kinds) != 1:
            raise ValueError(f"vary '{self.path}': give exactly one of grid, values, random, latin")
        if kinds[0] in ("random", "latin") and self.samples < 1:
            raise ValueError(f"vary '{self.path}': {kinds[0]} needs samples ≥ 1")
        if self.grid is not None and self.grid[2] < 1:
            raise ValueError(f"vary '{self.path}': grid count {self.grid[2]} must be ≥ 1")
        return self


class Study(_Table):
    """A study file (module docstring)."""

    name: str
    scene: str = "paper2005"
    seed: int = Field(0, ge=0)
    metrics: list[Literal[METRICS]] = [
        "eye_plane_merit",
        "safety",
    ]
    delta: float = Field(0.3, ge=0.0, lt=1.0)
    samples_per_pixel: int = Field(16, ge=1)
    vary: list[Vary] = []
    population: Population | None = None


def read_input_file(path: Path, kind: str, model: type[_Table]):
    """A TOML input file (a study, a dataset) read and validated as ``model``: SceneError in
    one line naming ``kind`` and the file, and the field and value, on bad input. The text as
    scene files take it: UTF-8 (BOM or not), or what an editor saved (UTF-16, Windows-1252)."""
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise SceneError(f"{kind} {p}: {exc.strerror or exc}") from None
    text = decode_text(raw, p, SceneError).lstrip("\ufeff")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{kind} {p}: not valid TOML: {exc}") from None
    try:
        return model.model_validate(data)
    except ValidationError as exc:  # the scene files' formatter, the TOML's own field names
        raise validation_error(exc, data, f"{kind} {p}", brackets=True) from None


def beside(path: Path, scene: str) -> str:
    """A scene named in an input file at ``path``: a preset as it is, a relative file path
    made absolute against that file's folder (its neighbour, not the current directory's)."""
    if scene in preset_names() or Path(scene).is_absolute():
        return scene
    return str((Path(path).parent / scene).absolute())


def load_study(path: str | Path) -> Study:
    """Read and validate a study file; SceneError naming the field and value on bad input."""
    p = Path(path)
    study = read_input_file(p, "study", Study)
    study = study.model_copy(update={"scene": beside(p, study.scene)})
    try:
        base = load_scene(study.scene)
    except EyelumeError as exc:
        raise SceneError(f"study {p}: field 'scene': {exc}") from None
    _check_runs(study, base, p)
    if study.population is not None:
        _check_population(study.population, base, p, study)
    return study


def _check_population(population: Population, base: Scene, path: Path, study: Study) -> None:
    """The population's distributions resolved on the base scene and its first person built
    (a mean outside its bounds, lids asked of a scene without them, a person whose eye cannot
    exist), and the ``tracking`` metric asked (what the people are evaluated by): SceneError
    naming the study file."""
    if "tracking" not in study.metrics:
        raise SceneError(
            "a [population] is evaluated by the 'tracking' metric: add it to metrics",
            file=f"study {path}",
            field="population",
        )
    try:
        sample_people(base, 1, population.seed, population)
    except EyelumeError as exc:
        raise SceneError(f"study {path}: field 'population': {exc}") from None


#: Most runs a study may plan: at seconds to minutes a run, 10⁵ runs is already days of work;
#: more is a typo (a grid count of 10⁸ ran silently for minutes building its list of runs).
MAX_RUNS = 100_000


def run_count(study: Study) -> int:
    """How many runs :func:`plan_runs` makes, without making them: the product of the grid,
    values and random axes' sizes, times the Latin-hypercube draws (their largest ``samples``)
    when there are any."""
    n = 1
    latin = [v.samples for v in study.vary if v.latin is not None]
    for v in study.vary:
        if v.grid is not None:
            n *= int(v.grid[2])
        elif v.values is not None:
            n *= len(v.values)
        elif v.random is not None:
            n *= v.samples
    return n * max(latin) if latin else n


def _check_runs(study: Study, base: Scene, path: Path) -> None:
    """Every value a study would run, checked before anything is written: each varied value
    alone (the error names ``vary[i].<kind>`` and the value), then every planned run's
    overrides together (a scene the values make only in combination). SceneError naming the
    study file, also for a study of more than :data:`MAX_RUNS` runs."""
    count = run_count(study)
    if count > MAX_RUNS:
        raise SceneError(
            f"{count:,} runs (the product of the varied parameters' sizes): more than "
            f"{MAX_RUNS:,}; vary fewer values",
            file=f"study {path}",
            field="vary",
        )
    runs = plan_runs(study)
    for i, v in enumerate(study.vary):
        kind = next(k for k in ("grid", "values", "random", "latin") if getattr(v, k) is not None)
        if kind in ("random", "latin"):
            probes = list(getattr(v, kind))  # both ends of the range
        else:
            probes = list(dict.fromkeys(r[v.path] for r in runs)) if runs else []
        for value in probes:
            try:
                apply_overrides(base, {v.path: value})
            except EyelumeError as exc:
                if not_a_path(exc, v.path):
                    raise SceneError(
                        "not a field of the scene (a dotted path such as leds.height_mm)",
                        file=f"study {path}", field=f"vary[{i}].path", value=v.path,
                    ) from None  # fmt: skip
                raise SceneError(
                    exc.message if exc.field else str(exc),
                    file=f"study {path}",
                    field=f"vary[{i}].{kind} ({v.path})",
                    value=value,
                ) from None
    for n, r in enumerate(runs):
        try:
            apply_overrides(base, r)
        except EyelumeError as exc:
            raise SceneError(
                f"run {n} ({', '.join(f'{k} = {x!r}' for k, x in r.items())}): {exc}",
                file=f"study {path}",
            ) from None


#: The last study planned (its JSON) and its runs: :func:`load_study` checks every planned run,
#: and ``eyelume study`` then runs them; the plan is made once (up to :data:`MAX_RUNS` runs).
_LAST_PLAN: tuple[str, list[dict]] | None = None


def plan_runs(study: Study) -> list[dict]:
    """The runs of a study: the product of the grid/values/random parameters, with the Latin-
    hypercube parameters drawn jointly (one draw per run of the product, or ``samples`` when
    nothing else varies). A fresh list of fresh dicts each call; the plan itself is made once
    for the same study (it depends on the study's fields only: the draws on its ``seed``)."""
    global _LAST_PLAN
    key = study.model_dump_json()
    if _LAST_PLAN is None or _LAST_PLAN[0] != key:
        _LAST_PLAN = (key, _plan(study))
    return [dict(r) for r in _LAST_PLAN[1]]


def _plan(study: Study) -> list[dict]:
    """:func:`plan_runs`, made anew."""
    rng = np.random.default_rng(study.seed)
    axes: list[tuple[str, list]] = []
    latin = [v for v in study.vary if v.latin is not None]
    for v in study.vary:
        if v.grid is not None:
            lo, hi, n = v.grid
            axes.append((v.path, [float(x) for x in np.linspace(lo, hi, int(n))]))
        elif v.values is not None:
            axes.append((v.path, list(v.values)))
        elif v.random is not None:
            lo, hi = v.random
            axes.append((v.path, [float(x) for x in rng.uniform(lo, hi, v.samples)]))
    runs = [dict(zip([a[0] for a in axes], combo, strict=True)) for combo in
            itertools.product(*[a[1] for a in axes])]  # fmt: skip
    if latin:
        from scipy.stats import qmc

        n = max(v.samples for v in latin)
        unit = qmc.LatinHypercube(d=len(latin), seed=rng).random(n)
        draws = [
            {v.path: float(v.latin[0] + u[j] * (v.latin[1] - v.latin[0])) for j, v in
             enumerate(latin)}
            for u in unit
        ]  # fmt: skip
        runs = [{**r, **d} for r in runs for d in draws]
    return runs


def run_key(base: Scene, overrides: dict, study: Study) -> str:
    """SHA-256 of everything a run's result depends on."""
    payload = {
        "scene": base.model_dump(mode="json"),
        "overrides": overrides,
        "metrics": sorted(study.metrics),
        "delta": study.delta,
        "samples_per_pixel": study.samples_per_pixel,
        "seed": study.seed,
    }
    if study.population is not None:  # absent otherwise: the keys of studies without one stay
        payload["population"] = study.population.model_dump(mode="json")
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()


def population_metrics(scene: Scene, study: Study) -> dict:
    """The ``tracking`` metric of a study with a ``[population]``: its people sampled on this
    run's ``scene`` (:func:`eyelume.scene.population.sample_population`: the same people, by
    their seed, in every run and worker), each evaluated — calibrated in their own eye — on the
    person grids (:func:`eyelume.optimize.tracking.evaluate_people`, the study's
    ``samples_per_pixel`` and ``seed``), and the distribution over them
    (:func:`eyelume.optimize.tracking.population_summary`): ``population_share_tracked``,
    ``population_score_mean_deg``, ``population_score_p95_deg`` (each person's mean PCCR error,
    a gaze without an estimate at 10°), ``population_pccr_mean_deg``, ``population_pccr_p95_deg``,
    ``population_detection_mean``, ``population_detection_p5``, ``population_people``."""
    from eyelume.optimize.tracking import evaluate_people, population_summary
    from eyelume.scene.population import sample_population

    people = sample_population(scene, study.population)
    results = evaluate_people(people, study.samples_per_pixel, study.seed)
    s = population_summary([r.row() for r in results])
    return {
        "population_people": s["people"],
        "population_share_tracked": s["share_tracked"],
        "population_score_mean_deg": s["score_deg"]["mean"],
        "population_score_p95_deg": s["score_deg"]["p95"],
        "population_pccr_mean_deg": s["pccr_mean_deg"]["mean"],
        "population_pccr_p95_deg": s["pccr_mean_deg"]["p95"],
        "population_detection_mean": s["detection_rate"]["mean"],
        "population_detection_p5": s["detection_rate"]["p5"],
    }


def _tracking_metrics(scene: Scene, study: Study) -> dict:
    """The ``tracking`` metric: over the study's people (:func:`population_metrics`) when it
    has a ``[population]``, else the scene's one eye over a 3 × 3 gaze grid, uncalibrated
    (``tracking_score_deg``: mean geometric gaze error, a failed frame at 10°;
    ``detection_rate``)."""
    if study.population is not None:
        return population_metrics(scene, study)
    from eyelume.analysis.tracking.evaluate import tracking_score
    from eyelume.optimize.tracking import GAZE_H, GAZE_V, evaluate_tracking

    rep = evaluate_tracking(scene, GAZE_H, GAZE_V, study.samples_per_pixel, study.seed,
                            calibrate=False)  # fmt: skip
    return {"tracking_score_deg": tracking_score(rep),
            "detection_rate": rep.summary["detection_rate"]}  # fmt: skip


def run_metrics(base: Scene, overrides: dict, study: Study) -> dict:
    """Compute the study's metrics for one run (a pure function of its inputs)."""
    from eyelume.analysis.safety import eye_safety

    scene = apply_overrides(base, overrides)
    out: dict = {}
    if "eye_plane_merit" in study.metrics:
        from eyelume.analysis.merit import generator_merit
        from eyelume.analysis.targets import gaussian_target
        from eyelume.estimators.closed_form import eye_plane_irradiance

        pattern = eye_plane_irradiance(scene)
        out["eye_plane_merit"] = float(
            generator_merit(pattern, gaussian_target(study.delta, scene.eye_plane))
        )
    if "eye_image_merit" in study.metrics or "skin_uniformity" in study.metrics:
        from eyelume.analysis.evaluator import skin_score
        from eyelume.analysis.masks import ideal_mask
        from eyelume.compile import compile_scene
        from eyelume.optimize.delta_study import evaluate_placement

        mask = ideal_mask(compile_scene(scene))
        result, merit, se, _ = evaluate_placement(scene, mask, study.samples_per_pixel, study.seed)
        if "eye_image_merit" in study.metrics:
            out["eye_image_merit"] = merit
            out["eye_image_merit_se"] = se
        if "skin_uniformity" in study.metrics:
            mean, std, cv = skin_score(result.eye_image, result.regions["skin"])
            out["skin_mean_w_mm2"], out["skin_cv"] = mean, cv
    if "tracking" in study.metrics:
        out.update(_tracking_metrics(scene, study))
    if "glints" in study.metrics:
        from eyelume.analysis.truth import glint_counts

        counts = np.asarray(glint_counts(scene)["visible"], dtype=float)
        out["glints_visible_min"] = float(counts.min())
        out["glints_visible_mean"] = float(counts.mean())
        out["gaze_share_all_glints"] = float(np.mean(counts == scene.leds.count))
    if "ghosts" in study.metrics:
        from eyelume.analysis.ghosts import false_glint_counts

        fg = false_glint_counts(scene)
        n = np.asarray(fg["false_glints"], dtype=float)
        out["false_glints_mean"] = float(n.mean())
        out["false_glints_max"] = int(n.max())

        def smallest(rows):
            vals = [x for row in rows for x in row if x is not None]
            return min(vals) if vals else None

        out["false_glint_to_glint_px_min"] = smallest(fg["nearest_glint_px"])
        out["false_glint_to_pupil_px_min"] = smallest(fg["pupil_px"])
    if "safety" in study.metrics:
        s = eye_safety(scene)
        out["corneal_margin"] = s["corneal_margin"]
        out["retinal_margin"] = s["retinal_margin"]
        out["within_exempt_group"] = bool(s["within_exempt_group"])
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v)
            for k, v in out.items()}  # fmt: skip
