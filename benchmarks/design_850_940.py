"""The same LED ring at 850 and at 940 nm over sampled people (issue 15, item 4): the README's
table of a design question answered end to end.

    python benchmarks/design_850_940.py                 # the issue's: 50 people, ~hours on 2 cores
    python benchmarks/design_850_940.py --people 4      # fewer
    python benchmarks/design_850_940.py --stop-at 23:20 # stop at that UTC time: the people done
    python benchmarks/design_850_940.py --set sensor.exposure_ms=1   # any scene field, both λ
    python benchmarks/design_850_940.py --keep DIR      # also save every frame's picture, truth;
                                                        # run again: the people kept there are
                                                        # read, not rendered (resume)
    python benchmarks/design_850_940.py --redetect DIR  # detection again on them, no render
                                                        # (the same --people and --set)

On ``vr-offaxis`` (its ring of 8 LEDs, nothing else changed but the wavelength), for each of N
people sampled from the anatomy distributions (``population.toml``, population seed 1, the same
draws at both wavelengths: the skin's reflectance range follows the wavelength, Cooksey, Allen
& Tsai 2017), this runs what ``eyelume evaluate-tracking --population N`` runs for a person
(:func:`eyelume.optimize.tracking.evaluate_people`: 9 calibration and 6 test frames, each
rendered to the sensor's own noise, ``--render-noise sensor``) at each wavelength:

* the scene's ``wavelength_nm`` (850 or 940), which the LEDs follow (``leds.wavelength_nm``
  unset), and with it the eye's indices (Atchison & Smith 2005), the tear film's reflection and
  the sampled skin reflectance;
* the sensor's QE from the built-in curve ``nir-global-shutter`` at the wavelength (the preset's
  one number, 0.30, would not follow it);
* sunlight on, as ``benchmarks/sunlight_850_940.py`` has it: AM1.5 direct, 40° above the
  headset's horizontal, 30° to the side, through a 40 nm band-pass about the LEDs (830–870 nm or
  920–960 nm). (A closed VR headset shields the eye from the sun; the sun here stands for the
  ambient light a see-through or leaky headset lets in, the issue's question.)

Per wavelength it reports:

* **detection rate**: the mean over people of the share of their test frames with pupil and
  every glint detected, and the share of people tracked (every test frame detected, every PCCR
  error ≤ 2°, :data:`eyelume.optimize.tracking.TRACKED_DEG`);
* **gaze error p95 (tracked people)**: the 95th percentile (numpy's linear interpolation) of the
  PCCR gaze errors of every test frame of the tracked people (visual axis against the fixated
  target, degrees);
* **glint signal to ambient**: per person the weakest glint's peak over the sunlight on its
  pixel in their worst test frame (``glint_signal_to_ambient_min``,
  :func:`eyelume.analysis.ambient.signal_to_ambient`); the median and the 5th percentile over
  people;
* **saturated pixels**: the median over the test frames of the share of the picture's pixels
  at the sensor's full scale (``Frame.saturated_share``): the sunlit face at the preset's 4 ms
  exposure fills the 6000 e⁻ well at 850 nm, not at 940 nm;
* **eye-safety margin** (:func:`eyelume.analysis.safety.eye_safety`, IEC 62471 exempt group):
  the corneal IR margin of the irradiance summed over the 8 LEDs, and the retinal thermal margin
  of the worst LED with the burn-hazard weight R(λ) at the wavelength. The margins are the
  headset's (nominal eye position), the same for every person.

With ``--keep DIR`` the run can be stopped and started again: ``DIR/run.json`` records what
the people's frames depend on (scene, population seed, render seed, render noise, ``--set``),
and a (person, wavelength) whose ``.npz`` and ``.json`` are in ``DIR`` is read from there
instead of rendered (its figures, CPU included, are the run's that made it). A ``DIR`` made
with other settings is refused (one line, exit 2). The people may so come from several
sessions' code; ``--redetect DIR`` analyses every kept picture again with one detector.

People run on ``--workers`` processes (the study's executor,
:func:`eyelume.optimize.runner.run_tasks`; each (person, wavelength) a task, a pure function of
its arguments). Ctrl-C, SIGTERM or ``--stop-at`` ends the run; the people finished at both
wavelengths are reported (their number is the N of the JSON line). Appends one JSON line to
``benchmarks/results/design_850_940.jsonl`` and prints the table.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import math
import os
import sys
import threading
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _common as C  # noqa: E402

RESULTS = Path(__file__).parent / "results" / "design_850_940.jsonl"
WAVELENGTHS = (850.0, 940.0)
SUN = {"ambient.sun.elevation_deg": 40.0, "ambient.sun.azimuth_deg": 30.0}
FILTERS = {850.0: (830.0, 870.0), 940.0: (920.0, 960.0)}


def scene_at(name: str, wavelength: float, overrides: dict | None = None):
    """The preset at ``wavelength`` with the QE curve, the band-pass filter and the sun, then
    ``overrides`` (``--set``: the same at both wavelengths)."""
    import eyelume

    lo, hi = FILTERS[wavelength]
    return eyelume.load_scene(
        name,
        {
            "wavelength_nm": wavelength,
            "sensor.quantum_efficiency": "nir-global-shutter",
            "sensor.filter.kind": "band_pass",
            "sensor.filter.cut_on_nm": lo,
            "sensor.filter.cut_off_nm": hi,
            **SUN,
            **(overrides or {}),
        },
    )


def person_task(person, seed: int, render_noise, keep: str | None = None, tag=None) -> dict:
    """One person at one wavelength: their row, their test frames' PCCR errors (None: no
    estimate) and glint signal to ambient, the renders' time and samples per pixel. ``keep``:
    a folder where the frames' digital pictures and truth are saved (:func:`save_frames`)."""
    from eyelume.optimize.tracking import evaluate_people

    t0, c0 = time.perf_counter(), time.process_time()
    (res,) = evaluate_people([person], 8, seed, render_noise=render_noise, keep_pictures=bool(keep))
    out = person_result(res, time.perf_counter() - t0, time.process_time() - c0)
    if keep:
        save_frames(Path(keep) / f"person{tag[0]:03d}_{tag[1]:.0f}nm", res.report, out)
    return out


def save_frames(stem: Path, report, result: dict) -> None:
    """A person's frames at one wavelength, kept (``--keep DIR``): ``stem.npz`` the digital
    pictures (frames, rows, cols) DN, calibration frames first, and ``stem.json`` per frame the
    gaze, truth, LEDs' layout and the render's measurements, with the person's result."""
    every = [*report.calibration, *report.frames]
    stem.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(
        stem.with_suffix(".npz"), counts=np.stack([f.picture["counts"] for f in every])
    )
    meta = {
        "calibration_frames": len(report.calibration),
        "render_budget": report.summary.get("render_budget"),
        "result": result,
        "frames": [
            {
                "gaze": list(f.gaze),
                "truth": f.truth,
                "led_azimuths_deg": list(f.picture["led_azimuths_deg"]),
                "led_pattern_px": None
                if f.picture["led_pattern_px"] is None
                else np.asarray(f.picture["led_pattern_px"]).tolist(),
                "render_s": f.render_s,
                "saturated_share": f.saturated_share,
                "samples_per_pixel": f.samples_per_pixel,
                "ambient": f.ambient,
                "calibration": f.calibration,
            }
            for f in every
        ],
    }
    stem.with_suffix(".json").write_text(json.dumps(meta, default=C._jsonable), encoding="utf-8")


def redetect_person(stem: Path, person) -> dict:
    """:func:`person_task`'s result for a person's kept frames (:func:`save_frames`), with
    detection and gaze estimation run again by this code on the same pictures; the render's
    figures (CPU, samples per pixel, saturation, signal to ambient) are the kept run's."""
    from types import SimpleNamespace

    from eyelume.analysis.tracking.evaluate import Frame
    from eyelume.optimize.tracking import PersonResult, reanalyse_report

    meta = json.loads(stem.with_suffix(".json").read_text(encoding="utf-8"))
    counts = np.load(stem.with_suffix(".npz"))["counts"]
    frames = []
    for c, m in zip(counts, meta["frames"], strict=True):
        f = Frame(tuple(m["gaze"]), None, m["truth"], render_s=m["render_s"])
        f.saturated_share, f.samples_per_pixel = m["saturated_share"], m["samples_per_pixel"]
        f.ambient, f.calibration = m["ambient"], m["calibration"]
        pattern = None if m["led_pattern_px"] is None else np.asarray(m["led_pattern_px"])
        f.picture = {
            "counts": c,
            "led_azimuths_deg": m["led_azimuths_deg"],
            "led_pattern_px": pattern,
        }
        frames.append(f)
    n = meta["calibration_frames"]
    kept = SimpleNamespace(
        frames=frames[n:], calibration=frames[:n], summary={"render_budget": meta["render_budget"]}
    )
    res = PersonResult(
        person.index, person.values, reanalyse_report(person.scene, kept), person.not_applied
    )
    old = meta["result"]
    return person_result(res, old["wall_s"], old["cpu_s"])


def _run_settings(a, noise, overrides: dict) -> dict:
    """What a kept person's frames depend on (``DIR/run.json``)."""
    return {
        "scene": a.scene,
        "population_seed": a.population_seed,
        "seed": a.seed,
        "render_noise": noise,
        "overrides": overrides,
        "sun": SUN,
        "filters_nm": {f"{w:.0f}": list(FILTERS[w]) for w in WAVELENGTHS},
    }


def _kept_settings(folder: Path, settings: dict) -> None:
    """Write ``folder/run.json`` or check that the one there matches ``settings`` (one line,
    exit 2, when it does not: a resumed run must not mix people rendered otherwise)."""
    path = folder / "run.json"
    want = json.loads(json.dumps(settings, default=C._jsonable))
    if path.exists():
        try:
            have = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            print(f"error: --keep {folder}: run.json unreadable ({exc})", file=sys.stderr)
            sys.exit(2)
        if have != want:
            diff = sorted(k for k in set(have) | set(want) if have.get(k) != want.get(k))
            print(
                f"error: --keep {folder}: its people were rendered with other settings ("
                + "; ".join(f"{k} {have.get(k)!r}, now {want.get(k)!r}" for k in diff)
                + "); use another folder",
                file=sys.stderr,
            )
            sys.exit(2)
        return
    folder.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(want, indent=1), encoding="utf-8")


def _kept_result(folder: Path, k: int, w: float) -> dict | None:
    """The result of (person ``k``, wavelength ``w``) kept in ``folder``, or None."""
    stem = folder / f"person{k:03d}_{w:.0f}nm"
    if not (stem.with_suffix(".npz").exists() and stem.with_suffix(".json").exists()):
        return None
    try:
        return json.loads(stem.with_suffix(".json").read_text(encoding="utf-8"))["result"]
    except (OSError, ValueError, KeyError):
        return None  # a half-written file: render that person again


def _resumed(a, noise, overrides: dict) -> dict:
    """The (person, wavelength) results already kept in ``--keep``'s folder (resume), after
    checking its settings (:func:`_kept_settings`); empty without ``--keep`` or with
    ``--redetect``."""
    done: dict = {}
    if not a.keep or a.redetect:
        return done
    _kept_settings(Path(a.keep), _run_settings(a, noise, overrides))
    for k in range(a.people):
        for w in WAVELENGTHS:
            kept = _kept_result(Path(a.keep), k, w)
            if kept is not None:
                done[(k, w)] = kept
    if done:
        print(f"   {len(done)} (person, wavelength) read from {a.keep}", flush=True)
    return done


def person_result(res, wall_s: float, cpu_s: float) -> dict:
    """The figures :func:`summarise` reads, from a person's :class:`PersonResult`."""
    frames = res.report.frames
    errors = [
        None if f.pccr is None else math.hypot(f.pccr[0] - f.gaze[0], f.pccr[1] - f.gaze[1])
        for f in frames
    ]
    sar = [
        f.ambient["glint_signal_to_ambient_min"]
        for f in frames
        if f.ambient is not None and f.ambient.get("glint_signal_to_ambient_min") is not None
    ]
    every = [*frames, *res.report.calibration]
    return {
        "row": res.row(),
        "pccr_errors_deg": errors,
        "glint_signal_to_ambient": sar,
        "wall_s": wall_s,
        "cpu_s": cpu_s,
        "render_s": sum(f.render_s for f in every),
        "samples_per_pixel": [f.samples_per_pixel for f in every],
        "saturated_share": [f.saturated_share for f in frames],
    }


def _pct(values, q: float) -> float | None:
    v = np.asarray([x for x in values if x is not None], dtype=float)
    return float(np.percentile(v, q)) if v.size else None


def summarise(done: list[dict], safety: dict) -> dict:
    """The table's figures at one wavelength over the people ``done`` (module docstring)."""
    rows = [d["row"] for d in done]
    tracked = [d for d in done if d["row"]["tracked"]]
    errors = [e for d in tracked for e in d["pccr_errors_deg"] if e is not None]
    person_sar = [min(d["glint_signal_to_ambient"]) for d in done if d["glint_signal_to_ambient"]]
    spp = [s for d in done for s in d["samples_per_pixel"]]
    return {
        "people": len(done),
        "detection_rate_mean": float(np.mean([r["detection_rate"] for r in rows])),
        "share_tracked": float(np.mean([r["tracked"] for r in rows])),
        "tracked_people": len(tracked),
        "gaze_error_p95_tracked_deg": _pct(errors, 95),
        "gaze_error_median_tracked_deg": _pct(errors, 50),
        "glint_signal_to_ambient_median": _pct(person_sar, 50),
        "glint_signal_to_ambient_p5": _pct(person_sar, 5),
        "people_with_ratio": len(person_sar),
        "corneal_margin_summed_leds": safety["corneal_margin"],
        "retinal_margin_worst_led": safety["retinal_margin"],
        "burn_hazard_weight": safety["burn_hazard_weight"],
        "corneal_irradiance_w_m2": safety["corneal_irradiance_w_m2"],
        "samples_per_pixel_range": [min(spp), max(spp)] if spp else None,
        "saturated_share_median": _pct([x for d in done for x in d.get("saturated_share", [])], 50),
        "cpu_s_per_person": float(np.mean([d["cpu_s"] for d in done])),
    }


def _args():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", default="vr-offaxis")
    ap.add_argument("--people", type=int, default=50)
    ap.add_argument("--population-seed", type=int, default=1)
    ap.add_argument("--seed", type=int, default=0, help="render seed of every frame")
    ap.add_argument("--render-noise", default="sensor", help="'sensor' or a relative error")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--stop-at", default=None, help="UTC HH:MM: stop then, report the people done")
    ap.add_argument(
        "--set",
        dest="sets",
        action="append",
        default=[],
        help="key=value scene override at both wavelengths, e.g. sensor.exposure_ms=1",
    )
    ap.add_argument(
        "--keep", default=None, help="folder: save every frame's digital picture and truth"
    )
    ap.add_argument(
        "--redetect",
        default=None,
        help="folder of a --keep run: detection and gaze again on its pictures (no render); "
        "give the same --people, --population-seed and --set",
    )
    return ap.parse_args()


def _stop_at(text: str) -> tuple[int, int]:
    """``--stop-at``'s (hour, minute) from 'HH:MM' (UTC), or one line and exit 2."""
    try:
        h, m = (int(x) for x in text.split(":"))
        if not (0 <= h < 24 and 0 <= m < 60):
            raise ValueError
    except ValueError:
        print(f"--stop-at {text!r}: must be a UTC time HH:MM (00:00 to 23:59)", file=sys.stderr)
        sys.exit(2)
    return h, m


def _stop_timer(stop_at: tuple[int, int] | None) -> None:
    """SIGINT to this process at ``stop_at`` (UTC (hour, minute), the next such time: tomorrow's
    when today's has passed): run_tasks stops its workers and
    the people finished are reported. Started in the background by a shell without job control
    (``… &`` in a script), a process inherits SIGINT ignored and Python installs no handler for
    it, so the timer's SIGINT (and Ctrl-C's) would do nothing: the handler is put back here."""
    if not stop_at:
        return
    import signal

    signal.signal(signal.SIGINT, signal.default_int_handler)

    now = dt.datetime.now(dt.UTC)
    at = now.replace(hour=stop_at[0], minute=stop_at[1], second=0, microsecond=0)
    if at <= now:  # 00:36 asked at 23:33: tomorrow's, not a stop at once
        at += dt.timedelta(days=1)
    delay = (at - now).total_seconds()
    t = threading.Timer(delay, os.kill, (os.getpid(), signal.SIGINT))
    t.daemon = True
    t.start()


def main() -> None:
    from eyelume.analysis.safety import eye_safety
    from eyelume.optimize.render_budget import parse_render_noise
    from eyelume.optimize.runner import run_tasks
    from eyelume.scene.population import sample_people

    a = _args()
    stop_at = _stop_at(a.stop_at) if a.stop_at else None
    noise = parse_render_noise(a.render_noise)
    info = {"machine": C.machine(), "command": C.command_line(), "load_start": C.loadavg()}
    C.print_header("850 vs 940 nm over sampled people (vr-offaxis ring)", info["machine"])
    from eyelume.errors import EyelumeError

    overrides = C.parse_sets(a.sets)
    try:
        scenes = {w: scene_at(a.scene, w, overrides) for w in WAVELENGTHS}
    except EyelumeError as exc:  # a bad --scene or --set: one line, exit 2
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
    people = {w: sample_people(scenes[w], a.people, a.population_seed) for w in WAVELENGTHS}
    safety = {w: eye_safety(scenes[w]) for w in WAVELENGTHS}
    done = _resumed(a, noise, overrides)
    resumed = list(done)
    tasks = (
        ((k, w), (people[w][k], a.seed, noise, a.keep, (k, w)))
        for k in range(a.people)
        for w in WAVELENGTHS
        if (k, w) not in done
    )
    t0 = time.perf_counter()

    def commit(tag, result) -> None:
        done[tag] = result
        r = result["row"]
        print(
            f"   person {tag[0]} at {tag[1]:.0f} nm: detection {r['detection_rate']:.0%}, "
            f"tracked {r['tracked']}, score {r['score_deg']:.2f}°, {result['cpu_s']:.0f} CPU-s "
            f"({time.perf_counter() - t0:.0f} s)",
            flush=True,
        )

    interrupted = False
    try:
        _stop_timer(stop_at)
        if a.redetect:  # the kept pictures of the people there, analysed again here
            for k in range(a.people):
                for w in WAVELENGTHS:
                    stem = Path(a.redetect) / f"person{k:03d}_{w:.0f}nm"
                    if stem.with_suffix(".npz").exists():
                        commit((k, w), redetect_person(stem, people[w][k]))
        else:
            run_tasks(person_task, tasks, commit, workers=a.workers)
    except KeyboardInterrupt:
        interrupted = True
    wall = time.perf_counter() - t0
    both = sorted(k for k in range(a.people) if all((k, w) in done for w in WAVELENGTHS))
    table = {
        f"{w:.0f} nm": summarise([done[(k, w)] for k in both], safety[w])
        for w in WAVELENGTHS
        if both
    }
    out = {
        "time_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        **info,
        "load_end": C.loadavg(),
        "scene": a.scene,
        "people_asked": a.people,
        "people_done": len(both),
        "people": both,
        "interrupted": interrupted,
        "population_seed": a.population_seed,
        "seed": a.seed,
        "render_noise": noise,
        "workers": a.workers,
        "wall_s": round(wall, 1),
        "sun": SUN,
        "overrides": overrides,
        "kept_in": a.keep,
        "resumed": len(resumed),
        "redetected_from": a.redetect,
        "filters_nm": {f"{w:.0f}": FILTERS[w] for w in WAVELENGTHS},
        "table": table,
        "rows": {f"{k[1]:.0f}/{k[0]}": v["row"] for k, v in sorted(done.items())},
    }
    print_table(table)
    print(f"   {len(both)} of {a.people} people at both wavelengths; {wall:.0f} s wall")
    RESULTS.parent.mkdir(exist_ok=True)
    with RESULTS.open("a", encoding="utf-8") as f:
        f.write(json.dumps(out) + "\n")
    print(f"appended to {RESULTS}", file=sys.stderr)


def print_table(table: dict) -> None:
    keys = [
        ("detection_rate_mean", "detection rate (mean over people)", "{:.1%}"),
        ("share_tracked", "people tracked", "{:.0%}"),
        ("gaze_error_p95_tracked_deg", "gaze error p95, tracked people (°)", "{:.2f}"),
        ("glint_signal_to_ambient_median", "glint signal/ambient, median", "{:.3g}"),
        ("glint_signal_to_ambient_p5", "glint signal/ambient, p5", "{:.3g}"),
        ("saturated_share_median", "saturated pixels (median test frame)", "{:.1%}"),
        ("corneal_margin_summed_leds", "corneal IR margin (8 LEDs summed)", "{:.3g}"),
        ("retinal_margin_worst_led", "retinal thermal margin (worst LED)", "{:.3g}"),
    ]
    print(f"{'':40s}" + "".join(f"{n:>12s}" for n in table))
    for k, label, fmt in keys:
        cells = [
            "—" if t[k] is None else fmt.format(t[k]) for t in table.values()
        ]  # fmt: skip
        print(f"{label:40s}" + "".join(f"{c:>12s}" for c in cells))


if __name__ == "__main__":
    main()
