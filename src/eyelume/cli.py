"""The ``eyelume`` command line (Typer). Thin: parses, calls the API, prints; no physics here.

Every error a user can cause is an :class:`~eyelume.errors.EyelumeError` (a bad option value is
an :class:`~eyelume.errors.OptionError`). They are caught in one place,
:meth:`_OneLineErrors.invoke` (after pbrt-v4's ``main``: errors surface to the top, which
prints them): a one-line message on stderr and exit code 2.
"""

from __future__ import annotations

import json
import math
import sys
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, NoReturn

import typer
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn
from typer.core import TyperGroup

from eyelume.errors import EyelumeError, EyelumeWarning, InputFileError, OptionError
from eyelume.scene.io import load_scene, preset_names
from eyelume.scene.model import Run

#: The model's cap on camera samples per pixel (``run.samples_per_pixel``), checked at the CLI.
_SAMPLES_CAP = next(
    m.le for m in Run.model_fields["samples_per_pixel"].metadata if getattr(m, "le", None)
)


class _PipeSafe:
    """``sys.stdout`` or ``sys.stderr`` (looked up at each write, as Rich's own console does)
    that swallows a broken pipe: ``eyelume render … | head -1`` closes the pipe after one line,
    and the command must still finish its work and write its files rather than stop (Click
    would exit 1 in silence). Once broken, the stream's later output is dropped;
    :meth:`_OneLineErrors.main` then points the descriptor at /dev/null so Python's final flush
    says nothing either."""

    broken = False

    def __init__(self, name: str) -> None:
        self._name = name

    @property
    def stream(self):
        return getattr(sys, self._name)

    def write(self, text: str) -> int:
        if not _PipeSafe.broken:
            try:
                self.stream.write(text)
            except BrokenPipeError:
                _PipeSafe.broken = True
        return len(text)

    def flush(self) -> None:
        if not _PipeSafe.broken:
            try:
                self.stream.flush()
            except BrokenPipeError:
                _PipeSafe.broken = True

    def __getattr__(self, name: str):  # isatty, fileno, encoding … of the stream itself
        return getattr(self.stream, name)


def _silence_broken_pipe() -> None:
    """After a broken pipe: stdout and stderr onto /dev/null, so the interpreter's last flush
    of the pipe raises nothing."""
    import os

    devnull = os.open(os.devnull, os.O_WRONLY)
    for stream in (sys.__stdout__, sys.__stderr__):
        try:
            os.dup2(devnull, stream.fileno())
        except (OSError, ValueError, AttributeError):
            pass
    os.close(devnull)


err = Console(file=_PipeSafe("stderr"))  # type: ignore[arg-type]
out_stream = _PipeSafe("stdout")

# Click's exception classes as Typer raises them: recent Typer vendors its own Click (the
# installed ``click`` package's classes are then other classes), older Typer re-exports Click's;
# typer.BadParameter is a UsageError, a ClickException, in both.
_UsageError = next(c for c in typer.BadParameter.__mro__ if c.__name__ == "UsageError")
_ClickException = next(c for c in typer.BadParameter.__mro__ if c.__name__ == "ClickException")


class _OneLineErrors(TyperGroup):
    """The command group; its :meth:`invoke` is the one place that reports an EyelumeError."""

    def invoke(self, ctx: typer.Context):
        with warnings.catch_warnings():
            warnings.simplefilter("always", EyelumeWarning)  # _show_warning says each once
            warnings.showwarning = _show_warning
            _SHOWN.clear()
            try:
                return super().invoke(ctx)
            except EyelumeError as exc:
                err.print(
                    f"[bold red]error:[/] {escape(str(exc))}", highlight=False, soft_wrap=True
                )
                raise typer.Exit(2) from None
            except KeyboardInterrupt:  # Ctrl-C or SIGTERM where a command keeps nothing partial
                err.print("interrupted")
                _exit_interrupted()

    def main(self, args=None, prog_name=None, complete_var=None, standalone_mode=True, **extra):
        """Click's usage errors (a missing or unknown option, a bad value) as one line on stderr
        and exit code 2, like every other bad input; Typer's standalone handling would draw a
        framed box of five lines. With ``standalone_mode=False`` the caller handles them."""
        if not standalone_mode:
            return super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        try:
            rv = super().main(args, prog_name, complete_var, standalone_mode=False, **extra)
        except _UsageError as exc:
            if not exc.format_message():  # no command given: the help is already printed
                sys.exit(exc.exit_code)
            where = exc.ctx.command_path if getattr(exc, "ctx", None) is not None else "eyelume"
            err.print(
                f"[bold red]error:[/] {escape(where)}: {escape(exc.format_message())} "
                f"(see {escape(where)} --help)",
                highlight=False,
                soft_wrap=True,
            )
            sys.exit(exc.exit_code)
        except _ClickException as exc:
            err.print(f"[bold red]error:[/] {escape(exc.format_message())}", soft_wrap=True)
            sys.exit(exc.exit_code)
        except typer.Abort:
            err.print("aborted")
            sys.exit(1)
        finally:
            if _PipeSafe.broken:
                _silence_broken_pipe()
        sys.exit(rv if isinstance(rv, int) else 0)


_show_default = warnings.showwarning
_SHOWN: set[str] = set()


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """An EyelumeWarning as one line ``warning: …`` on stderr, each distinct message once per
    command (a catalog read twice warns once); other warnings as Python shows them."""
    if issubclass(category, EyelumeWarning):
        text = str(message)
        if text not in _SHOWN:
            _SHOWN.add(text)
            err.print(f"[yellow]warning:[/] {escape(text)}", highlight=False, soft_wrap=True)
    else:
        _show_default(message, category, filename, lineno, file, line)


app = typer.Typer(
    cls=_OneLineErrors,
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Design the near-infrared illumination of an eye tracker in a head-mounted display.",
)

SceneOpt = Annotated[
    str,
    typer.Option(
        "--scene", help=f"A preset name ({', '.join(preset_names())}) or a scene TOML file."
    ),
]
SetOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--set", help="Override a scene field by its dotted path: key=value (repeatable)."
    ),
]


def _fail(message: str) -> NoReturn:
    """Refuse an option value: an OptionError, reported by :class:`_OneLineErrors`."""
    raise OptionError(message)


@app.callback()
def _main() -> None:
    # SIGTERM ends a command as Ctrl-C does: what is finished is kept, workers end, exit 143
    from eyelume.estimators.interrupt import sigterm_as_interrupt

    sigterm_as_interrupt()


def _overrides(pairs: list[str] | None) -> dict[str, str]:
    out = {}
    for pair in pairs or []:
        key, sep, value = pair.partition("=")
        if not sep or not key.strip():
            _fail(f"--set {pair!r}: expected key=value, e.g. leds.height_mm=40")
        out[key.strip()] = value.strip()
    return out


def _load(scene: str, sets: list[str] | None):
    return load_scene(scene, _overrides(sets))


def _warn_safety(safety: dict) -> None:
    """A red warning when the LEDs exceed an IEC 62471 exempt-group limit."""
    for key, what in (("corneal_margin", "corneal IR irradiance"), ("retinal_margin", "retinal "
                      "thermal radiance")):  # fmt: skip
        if safety[key] < 1:
            err.print(
                f"[bold red]warning:[/] {what} exceeds the IEC 62471 exempt-group limit "
                f"(margin {safety[key]:.2f})",
                highlight=False,
            )


#: A saturated share of the picture worth a warning: the glints alone are ~0.6 % at 87 × 65.
_SATURATION_WARN = 0.05


def _warn_saturation(summary_json: Path) -> None:
    """A warning naming the saturated share of the camera's picture when it is large, and
    whom to blame: the exposure when that many pixels saturate beyond the estimate's noise
    (``saturated_share_beyond_noise``, :func:`eyelume.detectors.sensor.camera_summary`),
    else that the render's rays or samples per pixel are too few to tell saturation from
    Monte Carlo noise (forward paper2005 at its 20 million rays: 11 % saturate, none beyond
    the noise)."""
    cam = json.loads(summary_json.read_text(encoding="utf-8")).get("camera", {})
    share = cam.get("saturated_share")
    if share is None or share <= _SATURATION_WARN:
        return
    beyond = cam.get("saturated_share_beyond_noise", share)
    if beyond > _SATURATION_WARN:
        err.print(
            f"[bold yellow]warning:[/] {share:.0%} of the camera's pixels saturate (full well or "
            "ADC full scale): the digital picture has lost that detail; shorten "
            "sensor.exposure_ms or dim the LEDs",
            highlight=False,
        )
    else:
        from eyelume.detectors.sensor import SATURATION_SIGMAS

        err.print(
            f"[bold yellow]warning:[/] {share:.0%} of the camera's pixels saturate (full well or "
            f"ADC full scale) but only {beyond:.1%} beyond the render's noise "
            f"({SATURATION_SIGMAS:g} standard errors): the rest may be Monte Carlo noise, "
            "too few rays per pixel to tell; trace more rays (--rays) or samples (--samples) "
            "before blaming the exposure",
            highlight=False,
        )


def _check_counts(samples: int, seed: int) -> None:
    """Refuse --samples below 1 or --seed below 0, naming the one that is wrong."""
    if samples < 1:
        _fail(f"--samples {samples}: must be ≥ 1 (camera samples per pixel)")
    if seed < 0:
        _fail(f"--seed {seed}: must be ≥ 0")


def _refuse_elements(sc, command: str) -> None:
    """The commands built on the paper's generator (``sweep-leds`` itself, ``reproduce``,
    ``optimize-tracking``) refuse a scene with optical elements before any work, naming them
    and the reason, in words that hold for any scene. The generator lights its eye plane in
    free space: an element between the LEDs and the eye (a spectacle lens) is ignored by it
    (``sweep-leds`` swept without them, saying nothing), so its δ-optimal placement, which
    the commands report, would be judged on a light that never reaches the eye. And the
    placements they move the paper's ring over (the generator's grid, distance 20–70 mm;
    optimize-tracking's 27, 50–70 mm) put the LEDs behind or beside the elements of a scene
    that has them near the eye: on paper2005-integrated 6 of optimize-tracking's 27 place an
    LED inside the camera's body and 19 send over 10⁻³ of an LED's light through or off the
    eyepiece or the hot mirror first (``compile.element_light_shares``), which the fast
    estimator refuses for a converging lens; 2 are free. The frames themselves would render
    and track (``evaluate-tracking`` does, through elements): a placement is judged that way,
    one at a time."""
    if sc.elements:
        names = ", ".join(
            f"elements.{k}" + (f" ({el.name})" if el.name else "")
            for k, el in enumerate(sc.elements)
        )
        _fail(
            f"{command} places LEDs by the paper's generator, whose eye plane is lit in free "
            f"space, and the scene has {names}, which it would ignore (what they refract, "
            "fold or reflect of the LEDs' light); and a grid of ring placements (distance "
            "20-70 mm) puts LEDs behind, inside or beside elements near the eye: take them "
            "out (--set elements=[]) to place LEDs for the free-space eye, or judge one "
            "placement at a time, with the elements, by "
            "`eyelume evaluate-tracking --set leds.distance_mm=...`"
        )


def _refuse_gaze(sets: list[str] | None, command: str) -> None:
    """The tracking commands turn the eye themselves: a --set of the gaze would be ignored."""
    for key in _overrides(sets):
        if key.startswith("eye.gaze_"):
            _fail(
                f"--set {key}: {command} sets the gaze itself (a grid over ±30° × ±20° and a "
                "calibration grid); leave it out, or use `eyelume render` for one gaze"
            )


#: Without a terminal (a log file, CI, ``nohup``) Rich draws no bar: a plain progress line is
#: written at most this often (seconds), and at the end.
_LINE_EVERY_S = 10.0


class _Progress(Progress):
    """Rich's progress bar; where stderr is no terminal, plain lines instead (label, count,
    elapsed, remaining): at most every :data:`_LINE_EVERY_S` s, once when a task finishes, and
    with ``announce`` whenever the task's description changes (each one a milestone, e.g. a
    wavelength group starting: none is throttled away), so a long run in a log still shows its
    progress."""

    def __init__(self, label: str, count: str, *columns, announce: bool = False, **kwargs):
        super().__init__(*columns, **kwargs)
        self._line = f"{label} {count}"
        self._last_line = -math.inf
        self._announce = announce
        self._said: str | None = None  # the description of the last line
        self._done: set = set()  # tasks whose finished line is said

    def update(self, task_id, **kwargs) -> None:  # type: ignore[override]
        super().update(task_id, **kwargs)
        if self.console.is_terminal:
            return
        task = self._tasks[task_id]
        if task.finished:
            return  # said once, by stop(), with the last description
        now = time.monotonic()
        new = self._announce and "description" in kwargs and task.description != self._said
        if now - self._last_line < _LINE_EVERY_S and not new:
            return
        self._last_line, self._said = now, task.description
        self._say(task)

    def stop(self) -> None:
        super().stop()
        if not self.console.is_terminal:
            for task in self.tasks:
                if task.finished and task.id not in self._done:
                    self._done.add(task.id)
                    self._say(task)

    def _say(self, task) -> None:
        left = None if task.finished else task.time_remaining
        when = f", {task.elapsed or 0.0:.0f} s" + (
            f", about {left:.0f} s left" if left is not None else ""
        )
        self.console.print(self._line.format(task=task) + when, highlight=False, soft_wrap=True)


def _progress_bar(label: str, count: str, announce: bool = False) -> Progress:
    """The one progress bar of every long command, on stderr: label, bar, count, elapsed, ETA
    (plain lines instead where stderr is no terminal: :class:`_Progress`, a line for each new
    description with ``announce``)."""
    return _Progress(
        label,
        count,
        TextColumn(label),
        BarColumn(),
        TextColumn(count),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        announce=announce,
        console=err,
        transient=True,
        disable=not err.is_terminal,  # no live bar (it left a blank line): _Progress's lines
    )


def _counting(bar: Progress, task) -> Callable[[str], None]:
    """A ``progress(message)`` callback for work that reports once per unit: each call advances
    the bar by one unit (its ETA from their pace) and shows the message."""

    def step(message: str) -> None:
        bar.update(task, advance=1, description=escape(message))

    return step


def _counted(label: str, total: int, what: str, fn, *args, **kwargs):
    """``fn(*args, progress=…, **kwargs)`` under a progress bar of ``total`` units."""
    count = f"{{task.completed}}/{{task.total}} {what}"
    with _progress_bar(f"[bold]{label}[/] {{task.description}}", count) as bar:
        task = bar.add_task("", total=total)
        return fn(*args, progress=_counting(bar, task), **kwargs)


def _interrupted_with_nothing(what: str) -> NoReturn:
    err.print(f"interrupted before {what} finished: nothing usable, no output")
    _exit_interrupted()
    raise AssertionError  # _exit_interrupted raises


def _check_out(out: Path, option: str = "--out") -> None:
    """Refuse an output folder that cannot take the outputs, before any work: an existing file,
    a path under a file, a place where nothing can be written (probed with a temporary file in
    the folder, or in its nearest existing parent when it is still to be created; nothing is
    left behind)."""
    import tempfile

    if out.exists() and not out.is_dir():
        _fail(f"{option} {out}: exists and is not a folder")
    probe = out.absolute()
    while not probe.exists():
        probe = probe.parent
    if not probe.is_dir():
        _fail(f"{option} {out}: {probe} is a file, not a folder")
    try:
        with tempfile.TemporaryFile(dir=probe):
            pass
    except OSError as exc:
        _fail(f"{option} {out}: cannot write in {probe} ({exc.strerror or exc})")


def _exit_interrupted() -> None:
    """Exit 128 + the signal that stopped the run: 130 after Ctrl-C, 143 after SIGTERM."""
    import signal

    from eyelume.estimators.interrupt import last_signal

    raise typer.Exit(128 + int(last_signal() or signal.SIGINT))


def _bytes(n: float) -> str:
    return f"{n / 2**20:,.0f} MiB" if n < 2**30 else f"{n / 2**30:.1f} GiB"


def _seconds(s: float) -> str:
    if s < 120:
        return f"{s:.0f} s"
    return f"{s / 60:.0f} min" if s < 7200 else f"{s / 3600:.1f} h"


def _warm_up_forward(cs) -> float | None:
    """Compile (or load) the forward tracer, saying so when it is the slow first compilation."""
    from eyelume.estimators import forward
    from eyelume.estimators.fast_run import kernels_cached
    from eyelume.render import check_sensor_spectra, warm_up_forward

    check_sensor_spectra(cs.scene)  # a bad QE table: one line before the long compilation
    kernel = getattr(forward, "_trace_batch", None)
    if kernel is not None and kernels_cached((kernel,)) is False:
        err.print("compiling kernels (first run only; one to two minutes)…")
    return _interruptible_compile(warm_up_forward, cs)


def _detect_kernels_cached() -> bool | None:
    """Whether Numba's cache holds any of the detector's compiled passes (glints.py, pupil.py):
    False when the first ``detect`` call of this machine will compile them (13.5 CPU-s measured at
    load 13), so that ``track`` says so instead of a silent pause."""
    from numba.core.registry import CPUDispatcher

    from eyelume.analysis.tracking import glints, pupil
    from eyelume.estimators.fast_run import kernels_cached

    disp = tuple(
        v for m in (glints, pupil) for v in vars(m).values() if isinstance(v, CPUDispatcher)
    )
    # a picture's path calls only some of them: one cached means this is not the first run
    states = [kernels_cached((d,)) for d in disp]
    return False if states and all(c is False for c in states) else True


def _warm_up(cs) -> float:
    """Compile (or load) the fast kernels, saying so when it is the slow first compilation."""
    from eyelume.estimators.fast_run import kernels_cached, warm_up
    from eyelume.render import check_sensor_spectra

    check_sensor_spectra(cs.scene)  # a bad QE table: one line before the long compilation
    if kernels_cached() is False:
        err.print("compiling kernels (first run only; one to two minutes)…")
    return _interruptible_compile(warm_up, cs)


def _interruptible_compile(fn, *args):
    """``fn(*args)`` (a kernel warm-up); Ctrl-C or SIGTERM during it exits 130 / 143 in one
    line, also when Numba turned the interrupt inside an LLVM callback into another error
    (a fresh user's Ctrl-C during the first compilation was a 344-line traceback, exit 1)."""
    from eyelume.estimators.interrupt import signal_seen

    with signal_seen() as flag:
        try:
            return fn(*args)
        except (KeyboardInterrupt, Exception):
            if not flag.requested:
                raise
    err.print("interrupted while compiling the kernels: nothing was written")
    _exit_interrupted()


@app.command()
def render(
    out: Annotated[Path, typer.Option("--out", help="Folder for the outputs (created).")],
    scene: SceneOpt = "paper2005",
    estimator: Annotated[
        str | None,
        typer.Option(help="fast or forward (default: forward with --rays, else run.estimator)."),
    ] = None,
    rays: Annotated[
        int | None, typer.Option(help="Forward: rays to trace (default: run.rays).")
    ] = None,
    samples: Annotated[
        int | None,
        typer.Option(help="Fast: camera samples per pixel (default: run.samples_per_pixel)."),
    ] = None,
    rel_error: Annotated[
        float | None,
        typer.Option(
            "--rel-error",
            help="Fast: add samples until the median skin pixel's relative standard error is "
            "at most this (e.g. 0.01), instead of a fixed count.",
        ),
    ] = None,
    max_samples: Annotated[
        int | None,
        typer.Option(
            "--max-samples",
            help="Fast, with --rel-error: stop at this many samples per pixel and say what was "
            "reached if the target needs more (default 4096).",
        ),
    ] = None,
    seed: Annotated[
        int | None, typer.Option(help="Random seed (default: the scene's run.seed).")
    ] = None,
    set_: SetOpt = None,
) -> None:
    """Render a scene and write the eye image (irradiance, its noise, the camera's digital
    reading), the eye-plane irradiance, pictures, layout and summary into OUT."""
    from eyelume.compile import compile_scene
    from eyelume.render import RenderOptions, check_estimator, render_extras
    from eyelume.render import render as render_scene
    from eyelume.report.outputs import write_render_outputs

    sc = _load(scene, set_)
    estimator = estimator or ("forward" if rays is not None else sc.run.estimator)
    _check_render_options(estimator, rays, samples, rel_error, max_samples, seed)
    _check_out(out)
    cs = compile_scene(sc)
    check_estimator(sc, estimator, cs)
    if max_samples is None:
        from eyelume.estimators.fast_run import MAX_SAMPLES_REL_ERROR

        max_samples = MAX_SAMPLES_REL_ERROR
    if estimator == "fast":
        result = _render_fast(cs, samples, rel_error, max_samples, seed)
    else:
        total = sc.run.rays if rays is None else rays
        t_load = _warm_up_forward(cs)
        err.print(f"tracing {total:,} rays of {sc.name} (Ctrl-C stops after the current batch)")
        with _progress_bar("[bold]tracing", "{task.completed:,}/{task.total:,} rays") as bar:
            task = bar.add_task("trace", total=total)
            result = render_scene(
                cs,
                RenderOptions(rays=rays, seed=seed, estimator="forward"),
                progress=lambda d, t: bar.update(task, completed=d),
            )
        if t_load:
            result.kernel_load_s = t_load
        if result.interrupted:
            err.print(f"interrupted: writing the {result.rays:,} rays traced so far")
    written = write_render_outputs(result, render_extras(cs, result.seed), out)
    summary = result.summary()
    _warn_safety(summary["safety"])
    _warn_saturation(out / "summary.json")
    skin = summary["regions"].get("skin", {})
    rel = skin.get("median_pixel_rel_error") if skin.get("pixels") else None
    noise = f"; median skin pixel ±{rel:.2%}" if rel is not None and math.isfinite(rel) else ""
    compiled = (
        f" (+ {result.kernel_load_s:.1f} s loading the kernels)"
        if result.kernel_load_s and result.kernel_load_s >= 0.5
        else ""
    )
    err.print(
        f"{result.rays:,} rays in {result.wall_time_s:.2f} s{compiled} ({result.estimator})"
        f"{noise}; "
        f"on the sensor {_sensor_w(summary['power_w']['sensor'])} of "
        f"{summary['power_w']['emitted']:.4g} W emitted; wrote {len(written)} files to {out}"
    )
    if "ambient" in summary:
        err.print(_ambient_line(summary["ambient"]), highlight=False)
    if result.ghost_warning:
        err.print(f"warning: {result.ghost_warning}", highlight=False, soft_wrap=True)
    if result.interrupted:
        _exit_interrupted()


def _sensor_w(w) -> str:
    """The power on the sensor, or why it is not known (a partial picture: pixels missing)."""
    return "an unknown power (pixels missing)" if w is None else f"{w:.3g} W"


def _ratio_text(x) -> str:
    return "unbounded (no ambient there)" if x is None else f"{x:.3g}"


def _ambient_line(amb: dict) -> str:
    """One line of the sunlight's signal to ambient (summary.json's ``ambient``)."""
    sun = amb["sun"]
    parts = [
        f"sunlight {sun['spectrum']} ({sun['seen_w_m2']:.3g} W/m² through the filter, "
        f"{sun['band_nm'][0]:g}-{sun['band_nm'][1]:g} nm)"
    ]
    if amb["glints"]:
        parts.append(f"glint/ambient min {_ratio_text(amb['glint_signal_to_ambient_min'])}")
        weakest = _ratio_text(amb["glint_peak_over_ambient_peak"])
        parts.append(f"weakest glint/sun's brightest pixel {weakest}")
    if amb["pupil"] is not None:
        parts.append(
            f"pupil-iris contrast/ambient {_ratio_text(amb['pupil']['signal_to_ambient'])}"
        )
    return "; ".join(parts)


def _check_render_options(estimator, rays, samples, rel_error, max_samples, seed) -> None:
    _check_budget(estimator, rays, samples, rel_error)
    cap = _SAMPLES_CAP
    if samples is not None and rel_error is not None:
        _fail(
            f"--samples {samples} with --rel-error {rel_error}: give one (a fixed count, or a "
            "target the run adds samples to reach; --max-samples caps it)"
        )
    if max_samples is not None and rel_error is None:
        _fail(f"--max-samples {max_samples}: caps a --rel-error run only (fixed: --samples)")
    if max_samples is not None and not 2 <= max_samples <= cap:
        _fail(
            f"--max-samples {max_samples}: must be 2 to {cap:,} (a --rel-error run's error is the "
            "scatter between two sample sets at least)"
        )
    if seed is not None and seed < 0:
        _fail(f"--seed {seed}: must be ≥ 0")


def _check_budget(estimator, rays, samples, rel_error) -> None:
    """The estimator and its budget: --rays for the forward one, --samples or --rel-error for
    the fast one; a budget given to the other estimator is refused naming the right option."""
    if estimator not in ("fast", "forward"):
        _fail(f"--estimator {estimator!r}: must be 'fast' or 'forward'")
    if rays is not None and (samples is not None or rel_error is not None):
        other = f"--samples {samples}" if samples is not None else f"--rel-error {rel_error}"
        _fail(
            f"--rays {rays} with {other}: give one (--rays is the forward estimator's budget, "
            "--samples and --rel-error the fast one's)"
        )
    if rays is not None and estimator != "forward":
        _fail(
            f"--rays {rays} with --estimator {estimator}: the fast estimator takes camera "
            "samples per pixel, not rays; give --samples N (or --estimator forward --rays N)"
        )
    for name, value in (("--samples", samples), ("--rel-error", rel_error)):
        if value is not None and estimator != "fast":
            _fail(
                f"{name} {value} with --estimator {estimator}: the forward estimator traces "
                "rays, not camera samples per pixel; give --rays N (or --estimator fast "
                f"{name} {value})"
            )
    if rays is not None and rays < 1:
        _fail(f"--rays {rays}: must be ≥ 1")
    cap = _SAMPLES_CAP
    if samples is not None and not 1 <= samples <= cap:
        _fail(f"--samples {samples}: must be 1 to {cap:,}")
    if rel_error is not None and not 0 < rel_error < 1:
        _fail(f"--rel-error {rel_error}: must be in (0, 1)")


def _render_fast(cs, samples, rel_error, max_samples, seed):
    """The fast estimator with a projection first (arrays, time from a pilot), a progress bar
    with an ETA, Ctrl-C/SIGTERM answered within about a second (nothing written when no sample
    set had finished), and a warning when a --rel-error target stops at --max-samples."""
    from eyelume.compile import wavelength_groups
    from eyelume.estimators.fast_run import (
        PILOT_ABOVE,
        array_bytes,
        first_round,
        pilot_rates,
        planned_sets,
    )
    from eyelume.render import RenderOptions
    from eyelume.render import render as render_scene

    sc = cs.scene
    asked = samples or sc.run.samples_per_pixel
    grid, sets = planned_sets(asked) if rel_error is None else first_round(asked, max_samples)
    t_load = _warm_up(cs)
    need = array_bytes(cs)
    avail = _available_memory()
    if avail is not None and need > avail:
        _fail(
            f"sensor {sc.sensor.cols} × {sc.sensor.rows}: the fast estimator needs "
            f"~{_bytes(need)} of arrays, {_bytes(avail)} are available: render fewer pixels"
        )
    pixels = sc.sensor.cols * sc.sensor.rows
    cam_rate, light_rate = pilot_rates(cs, sc.run.seed if seed is None else seed, grid)
    light_per_sample = sc.run.light_paths_per_pixel / 16
    groups = len(wavelength_groups(sc))  # each group is a whole render (render._render_groups)

    def projection(spp: int) -> str:
        s = groups * spp * pixels * (1 / cam_rate + light_per_sample / light_rate)
        each = f" ({groups} wavelength groups, a render each)" if groups > 1 else ""
        return f"~{_seconds(s)}{each} and ~{_bytes(need)} of arrays (a pilot's projection)"

    if rel_error is not None and pixels > PILOT_ABOVE:  # the pilot sizes the first round
        goal = (
            f"to a {rel_error * 100:.3g} % relative error in the median skin pixel of the "
            f"delivered picture, at most {max_samples:,} samples per pixel (first round sized "
            "by a pilot)"
        )
        plan = f"{projection(sets * grid * grid)} per {sets * grid * grid} samples per pixel"
    elif rel_error is not None:
        goal = (
            f"to a {rel_error * 100:.3g} % relative error in the median skin pixel of the "
            f"delivered picture, at most {max_samples:,} samples per pixel (first round "
            f"{sets * grid * grid})"
        )
        plan = f"first round {projection(sets * grid * grid)}"
    else:
        spp = sets * grid * grid
        note = "" if spp == asked else f" (asked {asked}: whole {grid}×{grid} sets, two at least)"
        goal = f"{spp} samples per pixel{note}"
        plan = projection(spp)
    err.print(f"rendering {sc.name} (fast estimator, {goal}); {plan}; Ctrl-C stops")
    label = "[bold]rendering[/] {task.description}"
    with _progress_bar(label, "{task.percentage:>3.0f}%", announce=True) as bar:
        task = bar.add_task("", total=None)
        try:
            result = render_scene(
                cs,
                RenderOptions(
                    seed=seed,
                    estimator="fast",
                    samples_per_pixel=samples,
                    rel_error=rel_error,
                    max_samples_per_pixel=max_samples,
                ),
                status=lambda msg: bar.update(task, description=msg),
                advance=lambda d, t: bar.update(task, completed=d, total=t),
            )
        except KeyboardInterrupt:
            bar.stop()
            err.print("interrupted before a camera sample set finished: nothing usable, no output")
            _exit_interrupted()
    if t_load:
        result.kernel_load_s = t_load
    if result.interrupted and result.covered_pixels is not None:
        err.print(
            f"interrupted in the first round: writing the {result.covered_pixels:,} of "
            f"{result.eye_image.size:,} pixels it finished ({result.samples_per_pixel} samples "
            "per pixel, from the top row); the rest are missing (NaN), marked partial"
        )
    elif result.interrupted:
        err.print(
            f"interrupted: writing the {result.samples_per_pixel} samples per pixel finished"
            + (
                " — one sample set only: the values are unbiased, their noise unknown"
                if result.variance_dof == 0
                else ""
            )  # fmt: skip
        )
    if result.target_reached is False:
        got = result.rel_error_achieved
        err.print(
            f"[yellow]warning:[/] --rel-error {rel_error:g} not reached within "
            f"{result.samples_per_pixel:,} samples per pixel (--max-samples {max_samples:,}): "
            + (f"reached {got:.4g}" if got is not None else "reached nothing"),
            highlight=False,
        )
    return result


def _available_memory() -> int | None:
    """Bytes of memory available now (Linux /proc/meminfo), or None when it cannot be read."""
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        return None
    return None


DeltaOpt = Annotated[
    float, typer.Option("--delta", help="Target falloff δ at the eye plane's corner (0 ≤ δ < 1).")
]


@app.command("sweep-leds")
def sweep_leds_cmd(
    out: Annotated[Path, typer.Option("--out", help="Folder for the outputs (created).")],
    scene: SceneOpt = "paper2005",
    delta: Annotated[
        float | None,
        typer.Option(
            "--delta",
            help="Target falloff δ at the eye plane's corner (0 ≤ δ < 1; default 0.3); not "
            "with --target.",
        ),
    ] = None,
    target: Annotated[
        Path | None,
        typer.Option(help="A user target pattern (.csv or .npy, the eye plane's rows × cols)."),
    ] = None,
    eye_safe: Annotated[
        bool, typer.Option(help="Exclude placements over an IEC 62471 exempt-group limit.")
    ] = False,
    set_: SetOpt = None,
) -> None:
    """The paper's generator (Section 4.1): the 385 LED placements (Y 20–40 mm, Z 20–70 mm,
    θ 0–30°) against a target eye-plane pattern, the best one refined, landscapes and the best
    pattern beside the target, into OUT."""
    from eyelume.analysis.targets import gaussian_target, load_target
    from eyelume.optimize.sweep import refine, sweep_leds
    from eyelume.report.optimize_outputs import sweep_caption, write_sweep_outputs

    if target is not None and delta is not None:
        _fail(f"--delta {delta} with --target {target}: give one (the target replaces δ's)")
    if delta is not None and not 0 <= delta < 1:
        _fail(f"--delta {delta}: must be in [0, 1)")
    delta = 0.3 if delta is None else delta
    sc = _load(scene, set_)
    _refuse_elements(sc, "sweep-leds")
    _check_out(out)
    try:
        goal = (
            load_target(target, sc.eye_plane)
            if target is not None
            else gaussian_target(delta, sc.eye_plane)
        )
    except (ValueError, OSError) as exc:
        _fail(str(exc))
    try:
        result = sweep_leds(sc, goal, eye_safe=eye_safe)
    except ValueError as exc:
        _fail(str(exc))
    b = result.best
    refined = refine(sc, goal, start=(b["height_mm"], b["distance_mm"], b["pitch_deg"]))
    plane = sc.eye_plane
    extent = (-plane.width_mm / 2, plane.width_mm / 2, -plane.height_mm / 2, plane.height_mm / 2)
    written = write_sweep_outputs(
        result, goal, refined, None if target is not None else delta, extent, out,
        caption=sweep_caption(sc.name),
    )  # fmt: skip
    err.print(
        f"best of {len(result.merit)}: Y {b['height_mm']:g} mm, Z {b['distance_mm']:g} mm, "
        f"θ {b['pitch_deg']:g}° (merit {b['merit']:.4g}); refined: Y {refined[0]:.2f}, "
        f"Z {refined[1]:.2f}, θ {refined[2]:.2f} (merit {refined[3]:.4g}); "
        f"wrote {len(written)} files to {out}"
    )


@app.command()
def reproduce(
    preset: Annotated[
        str, typer.Argument(help="The δ study's scene: a preset (paper2005, …) or a TOML file.")
    ],
    out: Annotated[Path, typer.Option("--out", help="Folder for the outputs (created).")],
    deltas: Annotated[
        str, typer.Option(help="Comma-separated δ values (the paper: 0 to 0.8 by 0.1).")
    ] = "0,0.1,0.2,0.3,0.4,0.5,0.6,0.7,0.8",
    samples: Annotated[
        int, typer.Option(help="Camera samples per pixel of each eye image (fast estimator).")
    ] = 32,
    seed: Annotated[int, typer.Option(help="Random seed of every render.")] = 0,
    direct: Annotated[
        int,
        typer.Option(
            help="Renders per search of the direct optimisation beyond the paper (0: skip)."
        ),
    ] = 30,
    direct_leds: Annotated[
        str | None,
        typer.Option(help="LED counts the direct optimisation tries, e.g. 4,6,8 (default 4)."),
    ] = None,
    vary_spread: Annotated[
        bool, typer.Option(help="Let the direct optimisation vary the LEDs' spread angle too.")
    ] = False,
    vary_azimuths: Annotated[
        bool, typer.Option(help="Let the direct optimisation move each LED's azimuth too.")
    ] = False,
    set_: SetOpt = None,
) -> None:
    """The paper's Section 4 δ study: for each δ the generator's best LEDs, their eye image (glints
    off), the evaluator's merit; the best δ, the direct optimum, and a comparison with the
    paper, into OUT."""
    from eyelume.compile import compile_scene
    from eyelume.optimize.delta_study import PAPER_CHOICE, PAPER_MERITS
    from eyelume.optimize.direct import DirectSearch
    from eyelume.report.optimize_outputs import write_delta_study_outputs

    sc = _load(preset, set_)
    try:
        values = [float(v) for v in deltas.split(",") if v.strip()]
    except ValueError:
        _fail(f"--deltas {deltas!r}: expected comma-separated numbers, e.g. 0,0.3,0.5")
    bad = [v for v in values if not 0 <= v < 1]
    if not values or bad:
        _fail(f"--deltas {deltas!r}: each δ must be in [0, 1)")
    _check_counts(samples=samples, seed=seed)
    if direct < 0:
        _fail(f"--direct {direct}: must be ≥ 0 (0 skips the direct optimisation)")
    _refuse_elements(sc, "reproduce")
    _refuse_without_direct(direct, direct_leds, vary_spread, vary_azimuths)
    direct_leds = "4" if direct_leds is None else direct_leds
    try:
        counts = [int(v) for v in direct_leds.split(",") if v.strip()]
    except ValueError:
        counts = []
    if not counts or any(not 1 <= n <= 12 for n in counts):
        _fail(f"--direct-leds {direct_leds!r}: expected LED counts from 1 to 12, e.g. 4,6,8")
    _check_out(out)
    compile_scene(sc)
    t0 = time.perf_counter()
    search = DirectSearch(
        led_counts=counts,
        vary_spread=vary_spread,
        vary_azimuths=vary_azimuths,
        samples_per_pixel=samples,
        seed=seed,
        max_evaluations=direct,
    )
    rows, paper, found, partial = _delta_study_parts(sc, values, samples, seed, search)
    best = min(rows, key=lambda r: r.evaluator_merit)
    meta = {
        "scene": sc.name,
        "samples_per_pixel": samples,
        "seed": seed,
        "deltas": values,
        "wall_time_s": round(time.perf_counter() - t0, 2),
        "paper_placement": paper,
        "eye_plane_mm": [sc.eye_plane.width_mm, sc.eye_plane.height_mm],
        "picture_mm": list(sc.sensor.field_mm),
    }
    if partial:
        meta["partial"] = partial
        meta["notes"] = f"**Partial run** ({partial}): what is here is all that finished."
    written = write_delta_study_outputs(rows, found, PAPER_MERITS, PAPER_CHOICE, meta, out)
    err.print(
        f"best δ = {best.delta:g} (Y {best.height_mm:g}, Z {best.distance_mm:g}, "
        f"θ {best.pitch_deg:g}); {meta['wall_time_s']} s; wrote {len(written)} files to {out}"
        + (f" — partial: {partial}" if partial else "")
    )
    if partial:
        _exit_interrupted()


def _delta_study_parts(sc, values, samples, seed, search):
    """(δ rows, the paper placement's evaluation, the direct optimum, a partial note or None):
    the δ study under a progress bar, then the paper's placement, then the direct search (if
    ``search.max_evaluations``). Ctrl-C or SIGTERM keeps the parts finished and says what was
    cut; before the first δ finished it ends the command (exit 130/143, nothing written)."""
    from eyelume.analysis.masks import ideal_mask
    from eyelume.compile import compile_scene
    from eyelume.estimators.interrupt import PartialRun, run_unit
    from eyelume.optimize.delta_study import evaluate_paper_placement, run_delta_study
    from eyelume.optimize.direct import optimize_direct

    try:
        rows = _counted("δ study", len(values), "δ", run_delta_study, sc, values, samples, seed)
    except PartialRun as exc:
        if not exc.done:
            _interrupted_with_nothing("the first δ")
        return exc.done, None, None, str(exc)
    paper = found = None
    try:
        err.print("the paper's placement (Y 40, Z 70, θ 20) in our model")
        paper = run_unit(evaluate_paper_placement, sc, samples, seed)
        if search.max_evaluations:
            best = min(rows, key=lambda r: r.evaluator_merit)
            searches = len(search.led_counts) * (2 if search.try_rotated else 1)
            err.print(f"direct optimisation of the eye image from δ = {best.delta:g}'s placement")
            found = _counted("direct", searches, "searches", optimize_direct, sc,
                             ideal_mask(compile_scene(sc)),
                             start=(best.height_mm, best.distance_mm, best.pitch_deg),
                             search=search)  # fmt: skip
    except KeyboardInterrupt:
        cut = "the direct optimisation" if paper is not None else "the paper's placement"
        return rows, paper, None, f"interrupted during {cut}"
    return rows, paper, found, None


def _refuse_without_direct(direct, direct_leds, vary_spread, vary_azimuths) -> None:
    """--direct 0 skips the direct optimisation: its own options would be silently ignored."""
    if direct:
        return
    given = [
        name
        for name, on in (
            (f"--direct-leds {direct_leds}", direct_leds is not None),
            ("--vary-spread", vary_spread),
            ("--vary-azimuths", vary_azimuths),
        )
        if on
    ]
    if given:
        _fail(f"{given[0]} with --direct 0: the direct optimisation is skipped; drop one")


def _load_picture_file(image: Path):
    """(array, channel order) of a picture file as stored: .npy by NumPy (no pickles), any
    other by OpenCV unchanged. InputFileError (one line) for a directory, a missing file, a
    file named .npy that is not one, or one OpenCV cannot read."""
    import numpy as np

    from eyelume.errors import InputFileError

    if image.is_dir():
        raise InputFileError("a directory, not a picture file", file=image)
    if not image.is_file():
        raise InputFileError("no such file", file=image)
    try:
        if image.suffix.lower() == ".npy":
            with image.open("rb") as fh:  # NumPy takes any other file for a pickle and says so
                if fh.read(6) != b"\x93NUMPY":
                    raise ValueError("not a NumPy .npy file (no .npy header)")
            return np.load(image, allow_pickle=False), "RGB"
        import cv2

        if image.suffix.lower() in (".jpg", ".jpeg"):
            # libjpeg decodes a cut file, fills the rest grey and only prints "Premature end of
            # JPEG file": a JPEG ends with its end-of-image marker, FF D9
            with image.open("rb") as fh:
                fh.seek(max(0, image.stat().st_size - 1024))  # padding after it: some cameras
                if b"\xff\xd9" not in fh.read():
                    raise ValueError("a JPEG cut short (no end-of-image marker)")
        log = cv2.utils.logging
        level = log.setLogLevel(log.LOG_LEVEL_SILENT)  # the one line below says it, not OpenCV's
        try:
            data = cv2.imread(str(image), cv2.IMREAD_UNCHANGED)
        finally:
            log.setLogLevel(level)
        if data is None:
            raise ValueError("not a picture OpenCV can read")
        return data, "BGR"
    except (ValueError, OSError) as exc:
        raise InputFileError(str(exc), file=image) from None


def _read_picture(image: Path):
    """A grey picture from a file a camera or eyelume writes: 8/16-bit PNG, TIFF, JPEG (OpenCV,
    unchanged depth) or .npy (any real dtype; NaN = missing pixels). Colour becomes luminance
    (Rec. 601 weights, OpenCV's) with a note. Bad files raise InputFileError (one line)."""
    import numpy as np

    from eyelume.errors import InputFileError

    data, order = _load_picture_file(image)
    if not isinstance(data, np.ndarray) or data.dtype.kind not in "biuf":
        raise InputFileError(
            f"not a numeric picture ({getattr(data, 'dtype', type(data))})", file=image
        )
    if data.size == 0:
        raise InputFileError(f"the picture is empty (shape {data.shape})", file=image)
    if data.ndim == 3 and data.shape[2] == 1:
        data = data[:, :, 0]
    if data.ndim == 3 and data.shape[2] in (3, 4):
        w = np.array([0.299, 0.587, 0.114])
        rgb = data[:, :, :3].astype(np.float64)
        data = rgb @ (w if order == "RGB" else w[::-1])
        err.print(f"note: {image} is a colour picture; using its luminance (Rec. 601 weights)")
    if data.ndim != 2:
        raise InputFileError(f"expected a 2-D grey picture, got shape {data.shape}", file=image)
    return data


#: The smallest largest-value a float picture may have: the detector's floors are absolute
#: (e.g. 1e-12 in the pupil's gradient normalisation), so a picture whose values are all below
#: this loses its glints and mis-sizes its pupil (1e-18 and below did) although its shape is
#: intact; such a picture is refused, naming the cause, instead of a wrong "ok".
MIN_FLOAT_PEAK = 1e-12


def _refuse_no_signal(data, image: Path) -> None:
    """InputFileError (exit 2) for a picture with no usable signal: no finite pixel above 0
    (no light), or a float picture whose largest value is below :data:`MIN_FLOAT_PEAK`."""
    import numpy as np

    finite = data[np.isfinite(data)] if data.dtype.kind == "f" else data
    if finite.size == 0:
        return  # detect refuses it (no valid pixel)
    peak = float(finite.max())
    if peak <= 0:
        raise InputFileError(f"no light: no pixel is above 0 (largest {peak:g})", file=image)
    if data.dtype.kind == "f" and peak < MIN_FLOAT_PEAK:
        raise InputFileError(
            f"no usable signal: the largest value is {peak:.3g}, below {MIN_FLOAT_PEAK:g} "
            "(the detector's thresholds need more); if this is a picture in some tiny unit, "
            "scale it (e.g. irradiance in W/m², or camera counts)",
            file=image,
        )


def _parse_leds(leds: str | None) -> list[float] | None:
    """LED azimuths from '0,90,180,270' (degrees, finite); None when not given."""
    import math

    if leds is None:
        return None
    try:
        az = [float(v) for v in leds.split(",")]
    except ValueError:
        az = []
    if not az or not all(math.isfinite(v) for v in az):
        raise OptionError(
            f"--leds {leds!r}: expected comma-separated finite degrees, e.g. 0,90,180,270"
        )
    seen = [round(v % 360.0, 9) % 360.0 for v in az]
    if len(set(seen)) != len(seen):
        raise OptionError(
            f"--leds {leds!r}: two LEDs at the same azimuth (modulo 360°): each LED's glint is "
            "told apart by its direction"
        )
    return az


def _track_led_layout(leds: str | None, scene: str | None, sets: list[str] | None):
    """``track``'s LED layout: (picture azimuths in degrees or None, the glints' predicted
    layout (k, 2) px or None, the scene's sensor or None) from ``--leds`` or from ``--scene``
    (and ``--set``), which exclude each other."""
    if scene is not None and leds is not None:
        _fail("--leds and --scene: give one (--scene takes the LEDs' layout from the scene)")
    if scene is None:
        if sets:
            _fail("--set needs --scene (it overrides a field of the scene)")
        return _parse_leds(leds), None, None
    from eyelume.analysis.tracking.evaluate import led_picture_azimuths, led_picture_pattern
    from eyelume.compile import compile_scene

    cs = compile_scene(_load(scene, sets))
    return led_picture_azimuths(cs), led_picture_pattern(cs), cs.scene.sensor


@app.command()
def track(
    image: Annotated[
        Path, typer.Argument(help="A grey eye picture: 8/16-bit .png, .tif, .jpg or .npy.")
    ],
    leds: Annotated[
        str | None,
        typer.Option(help="LED azimuths in degrees (0 = picture +x, 90 = up), e.g. 0,90,180,270."),
    ] = None,
    valid: Annotated[
        Path | None,
        typer.Option(help="Optional mask picture: non-zero where the picture shows the eye."),
    ] = None,
    scene: Annotated[
        str | None,
        typer.Option(
            "--scene",
            help="The scene (a preset or a TOML file) the picture was taken in: the LEDs' "
            "layout in the picture comes from it (instead of --leds; a fold mirror's "
            "left-right flip included).",
        ),
    ] = None,
    set_: SetOpt = None,
) -> None:
    """The detection pipeline on any grey eye picture: pupil ellipse and centre, glints with
    sub-pixel centroids matched to LEDs; prints JSON, and one line per failure. Non-finite
    pixels of a float .npy are missing pixels; a colour picture is read as its luminance. A
    picture enlarged k× by nearest neighbour (``render``'s PNGs of a small sensor) is read at
    its own size: positions are then in its original pixels (``"enlargement": k``), as in
    ``truth.json``. With ``--scene`` the LEDs' picture azimuths and glint layout are the
    scene's (:func:`eyelume.analysis.tracking.evaluate.led_picture_azimuths`,
    :func:`~eyelume.analysis.tracking.evaluate.led_picture_pattern`, as evaluate-tracking
    uses them) and the picture must be the scene's sensor size."""
    from eyelume.analysis.tracking.detect import detect, detection_to_dict, enlargement_factor
    from eyelume.errors import InputFileError

    azimuths, pattern, sensor = _track_led_layout(leds, scene, set_)
    data = _read_picture(image)
    mask = None
    if valid is not None:
        mask = _read_picture(valid) != 0
        if mask.shape != data.shape:
            raise InputFileError(
                f"mask shape {mask.shape} differs from the picture's {data.shape}", file=valid
            )
    _refuse_no_signal(data, image)
    k = enlargement_factor(data)
    if k > 1:
        data = data[::k, ::k]
        mask = None if mask is None else mask[::k, ::k]
        err.print(
            f"note: {image.name} is enlarged {k}× by nearest neighbour from a "
            f"{data.shape[1]} × {data.shape[0]} picture; detecting on that picture, positions "
            f"in its pixels (x_file = {k} x + {(k - 1) / 2:g})",
            highlight=False,
            soft_wrap=True,
        )
    if sensor is not None and data.shape != (sensor.rows, sensor.cols):
        raise InputFileError(
            f"the picture is {data.shape[1]} × {data.shape[0]} pixels, the scene's sensor "
            f"{sensor.cols} × {sensor.rows} (--scene {scene}): the LEDs' layout in pixels "
            "would not fit it",
            file=image,
        )
    if _detect_kernels_cached() is False:
        err.print("compiling detection kernels (first run only; about 15 s)…")
    try:
        result = detect(data, led_azimuths_deg=azimuths, valid=mask, led_pattern_px=pattern)
    except ValueError as exc:
        raise InputFileError(str(exc), file=image) from None
    from eyelume.json_files import dumps

    out_stream.write(dumps({**detection_to_dict(result), "enlargement": k}) + "\n")
    for reason in result.failures:
        err.print(f"[yellow]{escape(reason)}[/]", highlight=False, soft_wrap=True)
    if image.name == "eye_image.png" and not result.ok:
        err.print(
            f"note: {image.name} is render's display picture of the irradiance (clipped at its "
            "99.5th percentile, so the glints saturate with the brightest skin), not a camera's; "
            "track eye_image_digital.png or eye_image_digital.npy beside it (the camera's "
            "reading)",
            highlight=False,
            soft_wrap=True,
        )


@app.command("evaluate-tracking")
def evaluate_tracking_cmd(
    out: Annotated[Path, typer.Option("--out", help="Folder for the outputs (created).")],
    scene: SceneOpt = "paper2005",
    samples: Annotated[
        int | None,
        typer.Option(
            help="Camera samples per pixel of each rendered frame (default 16; with "
            "--population the default is --render-noise sensor)."
        ),
    ] = None,
    render_noise: Annotated[
        str | None,
        typer.Option(
            help="Render each frame to a noise instead of --samples: 'sensor' (the sensor's own "
            "shot noise on the skin, from one pilot render per person or scene; the default "
            "with --population: a tracker sees the sensor's noise, rendering below it is "
            "wasted) or a relative error such as 0.05."
        ),
    ] = None,
    seed: Annotated[int, typer.Option(help="Random seed of every frame.")] = 0,
    population: Annotated[
        int,
        typer.Option(
            help="Sample N people from the anatomy distributions (population.toml) and report "
            "the distribution over them: population.json, people.csv (0: the scene's one eye)."
        ),
    ] = 0,
    population_seed: Annotated[
        int | None,
        typer.Option(help="Seed of the people (default: the population file's, else 0)."),
    ] = None,
    population_file: Annotated[
        Path | None,
        typer.Option(
            help="TOML with a [population] table (a study file serves): conditions, "
            "parameters, distributions; its size and seed unless given here."
        ),
    ] = None,
    tracked_deg: Annotated[
        float,
        typer.Option(help="A person is tracked: every test gaze detected, PCCR error ≤ this (°)."),
    ] = 2.0,
    named_population: Annotated[
        bool,
        typer.Option(
            help="Also over a fixed, named population: iris dark/light, skin dark/light, narrow "
            "lids, headset slip ±2 mm after calibration (one folder each)."
        ),
    ] = False,
    workers: Annotated[
        int,
        typer.Option(help="With --population: people on this many processes (same results)."),
    ] = 1,
    set_: SetOpt = None,
) -> None:
    """Tracking quality of the scene's illumination: render the eye over a 7 × 5 gaze grid
    (and a 3 × 3 calibration grid), detect pupil and glints on the camera's images, estimate
    gaze (PCCR, Guestrin–Eizenman) and compare with the truth; table, summary and error maps
    into OUT. With --population N: N sampled people instead, each on a 3 × 2 test grid after
    their own 3 × 3 calibration, and the distribution over them."""
    from eyelume.analysis.tracking.evaluate import failure_reason
    from eyelume.compile import compile_scene
    from eyelume.render import check_estimator
    from eyelume.report.tracking_outputs import write_tracking_outputs

    _refuse_gaze(set_, "evaluate-tracking")
    sc = _load(scene, set_)
    sampled = _people_options(population, population_seed, population_file, tracked_deg,
                              named_population)  # fmt: skip
    samples, noise = _tracking_budget(samples, render_noise, sampled is not None)
    _check_counts(samples=samples, seed=seed)
    if not 1 <= workers <= 256:
        _fail(f"--workers {workers}: must be 1 to 256 processes")
    if workers > 1 and sampled is None:
        _fail(f"--workers {workers}: only with --population (the people run in parallel)")
    check_estimator(sc, "fast", compile_scene(sc), command="evaluate-tracking")
    _check_out(out)
    if sampled is not None:
        _people_run(sc, *sampled, samples, seed, tracked_deg, out, noise, workers)
        return
    t0 = time.perf_counter()
    report, partial = _tracking_parts(sc, samples, seed, named_population, out, noise)
    meta = {
        "scene": sc.name,
        "samples_per_pixel": samples if noise is None else None,
        "render_noise": noise,
        "render_budget": report.summary.get("render_budget"),
        "seed": seed,
        "sensor": [sc.sensor.cols, sc.sensor.rows],
        "wall_time_s": round(time.perf_counter() - t0, 2),
    }
    if partial:
        meta["partial"] = partial
    written = write_tracking_outputs(report, meta, out)
    s = report.summary
    gp, gg = s["gaze_pccr"], s["gaze_geometric"]
    pe = s["pupil_error_px"]["mean"]
    why = failure_reason(s)

    def deg(stats: dict) -> str:
        if stats.get("not_applicable"):
            return "none (no model through the optical elements)"
        return f"{stats['mean_deg']:.3g}° mean" if stats.get("mean_deg") is not None else "none"

    suspect = sum(s[k].get("ok_frames_with", 0) for k in ("rim_glints", "stray_glints"))
    err.print(
        f"detection {s['detection_rate']:.0%}"
        + (f" ({why})" if why else "")
        + (
            f", {s['clean_detection_rate']:.0%} with every matched glint whole (ok frames "
            f"with a glint cut by the cornea's rim: {s['rim_glints']['ok_frames_with']}, "
            f"with a stray: {s['stray_glints']['ok_frames_with']})"
            if suspect
            else ""
        )
        + f"; pupil error {f'{pe:.3g} px' if pe is not None else 'none'}; "
        f"gaze PCCR {deg(gp)}, geometric {deg(gg)}; {meta['wall_time_s']} s; "
        f"wrote {len(written)} files to {out}" + (f" — partial: {partial}" if partial else ""),
        highlight=False,
    )
    if "signal_to_ambient" in s:
        err.print(_tracking_ambient_line(s["signal_to_ambient"]), highlight=False)
    if partial:
        _exit_interrupted()


def _tracking_ambient_line(rated: dict) -> str:
    """One line of the frames' signal to ambient (the tracking summary's ``signal_to_ambient``:
    the smallest over the frames)."""
    names = {
        "glint_signal_to_ambient_min": "glint/ambient",
        "glint_peak_over_ambient_peak": "weakest glint/sun's brightest pixel",
        "pupil_signal_to_ambient": "pupil-iris contrast/ambient",
    }
    parts = [
        f"{label} min {rated[key]['min']:.3g} over {rated[key]['frames']} frames"
        for key, label in names.items()
        if rated[key]["frames"]
    ]
    return "sunlight: " + ("; ".join(parts) if parts else "no ratio bounded (no ambient there)")


def _tracking_budget(samples: int | None, noise: str | None, people: bool):
    """(samples per pixel, render_noise or None) of evaluate-tracking's --samples and
    --render-noise: both refused together; neither: 'sensor' over sampled people, else 16
    samples per pixel."""
    from eyelume.optimize.render_budget import parse_render_noise

    if samples is not None and noise is not None:
        _fail(f"--samples {samples} and --render-noise {noise}: give one render budget")
    if noise is not None:
        return 16, parse_render_noise(noise)
    if samples is None:
        return (16, "sensor") if people else (16, None)
    return samples, None


def _people_options(n: int, seed: int | None, path: Path | None, tracked_deg: float,
                    named: bool):  # fmt: skip
    """(Population, size, seed) of --population/--population-seed/--population-file, or None
    without them; bad values refused in one line (OptionError, or the file's SceneError)."""
    from eyelume.scene.population import Population, load_population_file

    if n < 0:
        _fail(f"--population {n}: must be ≥ 0 (people)")
    if seed is not None and not 0 <= seed < 2**63:
        _fail(f"--population-seed {seed}: must be ≥ 0")
    if not (math.isfinite(tracked_deg) and tracked_deg > 0):
        _fail(f"--tracked-deg {tracked_deg}: must be a positive number of degrees")
    if n == 0 and path is None:
        if seed is not None:
            _fail("--population-seed needs --population N or --population-file")
        return None
    if named:
        _fail("--named-population and --population/--population-file: choose one")
    pop = load_population_file(path) if path is not None else Population()
    size = n if n > 0 else pop.size
    if size > 100_000:
        _fail(f"--population {size}: at most 100000 people")
    return pop, size, seed if seed is not None else pop.seed


def _people_run(sc, pop, size: int, pop_seed: int, samples: int, seed: int, tracked_deg: float,
                out: Path, noise: str | float | None = None, workers: int = 1) -> None:  # fmt: skip
    """evaluate-tracking over ``size`` sampled people: progress with an ETA, population.json and
    people.csv; Ctrl-C or SIGTERM keeps the people finished (nothing before the first)."""
    from eyelume.estimators.interrupt import PartialRun
    from eyelume.optimize.tracking import evaluate_people, people_frame_count, population_summary
    from eyelume.report.tracking_outputs import write_people_outputs
    from eyelume.scene.population import resolved_distributions, sample_people

    people = sample_people(sc, size, pop_seed, pop)
    t0 = time.perf_counter()
    partial = None
    try:
        results = _counted("people", size * people_frame_count(), "frames", evaluate_people,
                           people, samples_per_pixel=samples, seed=seed,
                           render_noise=noise, workers=workers)  # fmt: skip
    except PartialRun as exc:
        if not exc.done:
            _interrupted_with_nothing("the first person")
        results, partial = exc.done, str(exc)
    rows = [r.row(tracked_deg) for r in results]
    summary = population_summary(rows, tracked_deg)
    dists = resolved_distributions(sc, pop)
    used = [r["render_budget"]["samples_per_pixel_used"] for r in rows if r.get("render_budget")]
    meta = {
        "scene": sc.name,
        "samples_per_pixel": samples if noise is None else None,
        "render_noise": noise,
        "workers": workers,
        "samples_per_pixel_used": [min(u[0] for u in used), max(u[1] for u in used)]
        if used and all(used)
        else None,
        "seed": seed,
        "sensor": [sc.sensor.cols, sc.sensor.rows],
        "population_seed": pop_seed,
        "population": pop.model_dump(mode="json") | {"size": size, "seed": pop_seed},
        "parameters_used": list(pop.used),
        "distributions": {k: vars(d) for k, d in dists.items()},
        "wall_time_s": round(time.perf_counter() - t0, 2),
    }
    if partial:
        meta["partial"] = partial
    written = write_people_outputs(rows, summary, meta, out)
    sc_ = summary["score_deg"]
    err.print(
        f"{summary['people']} of {size} people: tracked {summary['share_tracked']:.0%} (every "
        f"test gaze detected, PCCR ≤ {tracked_deg:g}°); gaze score mean {sc_['mean']:.3g}°, "
        f"p95 {sc_['p95']:.3g}°; detection mean {summary['detection_rate']['mean']:.0%}; "
        f"{meta['wall_time_s']} s; wrote {len(written)} files to {out}"
        + (f" — partial: {partial}" if partial else ""),
        highlight=False,
    )
    if partial:
        _exit_interrupted()


def _tracking_parts(sc, samples: int, seed: int, population: bool, out: Path, noise=None):
    """(the nominal report, a partial note or None) of evaluate-tracking under a progress bar
    with an ETA, the population's folders written when asked. Ctrl-C or SIGTERM keeps the
    gazes (or population members) finished; before any, the command ends (nothing written)."""
    from eyelume.estimators.interrupt import PartialRun
    from eyelume.optimize.tracking import (
        POPULATION,
        evaluate_population,
        evaluate_tracking,
        frame_count,
        member_line,
    )
    from eyelume.report.tracking_outputs import write_population_outputs

    frames = frame_count()
    partial = None
    if not population:
        try:
            report = _counted("tracking", frames, "frames", evaluate_tracking, sc,
                              samples_per_pixel=samples, seed=seed,
                              render_noise=noise)  # fmt: skip
        except PartialRun as exc:
            if exc.done is None:
                _interrupted_with_nothing("the first test gaze")
            report, partial = exc.done, str(exc)
        return report, partial
    try:
        total = frames * len(POPULATION)
        members = _counted("population", total, "frames", evaluate_population, sc,
                           samples_per_pixel=samples, seed=seed,
                           render_noise=noise)  # fmt: skip
    except PartialRun as exc:
        if "nominal" not in exc.done:
            _interrupted_with_nothing("the nominal member")
        members, partial = exc.done, str(exc)
    for name, rep in members.items():
        err.print(member_line(name, rep), highlight=False)
    write_population_outputs(
        members, sc.name, out, partial,
        {"samples_per_pixel": samples if noise is None else None, "render_noise": noise,
         "seed": seed, "sensor": [sc.sensor.cols, sc.sensor.rows]},
    )  # fmt: skip
    return members["nominal"], partial


@app.command("optimize-tracking")
def optimize_tracking_cmd(
    out: Annotated[Path, typer.Option("--out", help="Folder for the outputs (created).")],
    scene: SceneOpt = "paper2005",
    delta: DeltaOpt = 0.3,
    samples: Annotated[int, typer.Option(help="Camera samples per pixel per frame.")] = 8,
    seed: Annotated[int, typer.Option(help="Random seed of every frame.")] = 0,
    set_: SetOpt = None,
) -> None:
    """Choose the LEDs for tracking itself: 27 placements scored by the gaze error of the whole
    pipeline over 9 gazes, against the generator's δ-optimal placement and the paper's."""
    from eyelume.analysis.targets import gaussian_target
    from eyelume.compile import compile_scene
    from eyelume.estimators.interrupt import PartialRun
    from eyelume.optimize.sweep import sweep_leds
    from eyelume.optimize.tracking import sweep_tracking
    from eyelume.report.optimize_outputs import write_tracking_sweep_outputs

    _refuse_gaze(set_, "optimize-tracking")
    sc = _load(scene, set_)
    _check_counts(samples=samples, seed=seed)
    if not 0 <= delta < 1:
        _fail(f"--delta {delta}: must be in [0, 1)")
    _refuse_elements(sc, "optimize-tracking")
    compile_scene(sc)  # a camera that sees no eye: one line, not 29 placements scored inf
    _check_out(out)
    b = sweep_leds(sc, gaussian_target(delta, sc.eye_plane)).best
    dopt = (b["height_mm"], b["distance_mm"], b["pitch_deg"])
    partial = None
    try:
        rows, best, d_row, paper = _counted("placements", 27 + 2, "placements", sweep_tracking,
                                            sc, dopt, samples=samples, seed=seed)  # fmt: skip
    except PartialRun as exc:
        (rows, d_row, paper), partial = exc.done, str(exc)
        if not rows:
            _interrupted_with_nothing("the first placement")
        best = min(rows, key=lambda r: r.score_deg)
    meta = {
        "delta": delta,
        "samples_per_pixel": samples,
        "seed": seed,
        "sensor": [sc.sensor.cols, sc.sensor.rows],
    }
    if partial:
        meta["partial"] = partial
    write_tracking_sweep_outputs(rows, best, d_row, paper, meta, out)

    def score(r) -> str:
        return "not scored" if r is None else f"{r.score_deg:.2f}°"

    err.print(
        f"tracking-optimal: Y {best.height_mm:g} Z {best.distance_mm:g} θ {best.pitch_deg:g} "
        f"({best.score_deg:.2f}°); δ-optimal {score(d_row)}; paper {score(paper)}"
        + (f" — partial: {partial}" if partial else "")
    )
    if partial:
        _exit_interrupted()


# The options `study` and `dataset` share (the executor's checked by _check_executor).
ResumeOpt = Annotated[
    bool,
    typer.Option(
        help="Continue in OUT: what is finished there is kept and skipped (after Ctrl-C, "
        "SIGTERM, a crash or kill -9)."
    ),
]
WorkersOpt = Annotated[
    int | None, typer.Option(help="Worker processes (default: every core).")
]  # fmt: skip
DaskOpt = Annotated[
    str | None,
    typer.Option(
        help="Run on Dask: 'local' starts a LocalCluster, else a scheduler address (refused "
        "when none answers within 5 s)."
    ),
]
LockTimeoutOpt = Annotated[
    float,
    typer.Option(
        "--lock-timeout",
        help="Seconds a commit waits (after SQLite's 5 s) while another program holds the "
        "store's write lock, before the run stops (exit 2; --resume continues).",
    ),
]


@app.command()
def study(
    study_file: Annotated[Path, typer.Argument(help="The study file (TOML).")],
    out: Annotated[Path, typer.Option("--out", help="The study's folder (its result store).")],
    resume: ResumeOpt = False,
    workers: WorkersOpt = None,
    dask: DaskOpt = None,
    lock_timeout: LockTimeoutOpt = 60.0,
) -> None:
    """Run a study: the base scene with parameters varied by their dotted paths, metrics per
    run, each finished run committed at once to OUT/results.sqlite (resumable)."""
    from eyelume.optimize.runner import run_study
    from eyelume.optimize.study import load_study, run_count
    from eyelume.report.optimize_outputs import write_study_table

    st = load_study(study_file)
    _check_executor(workers, dask, lock_timeout)
    _check_out(out)
    if (Path(out) / "results.sqlite").exists():
        from eyelume.optimize.store import check_store

        # a damaged store, or finished runs without --resume: one line before the banner
        finished = check_store(out)
        if finished and not resume:
            _fail(f"{out}: holds {finished} finished runs; use --resume or a new --out")
    total = run_count(st)
    err.print(f"study {st.name}: {total} runs into {out} (Ctrl-C, then --resume, loses nothing)")
    with _progress_bar("[bold]runs", "{task.completed}/{task.total}") as bar:
        task = bar.add_task("study", total=total)
        try:
            rows = run_study(
                st,
                out,
                workers,
                resume,
                lambda d, t: bar.update(task, completed=d),
                dask,
                lock_timeout_s=lock_timeout,
                note=lambda msg: err.print(f"[yellow]{msg}[/]", highlight=False),
            )
        except (ValueError, OSError) as exc:
            bar.stop()
            _fail(str(exc))
        except KeyboardInterrupt:
            bar.stop()
            err.print(f"interrupted: the finished runs are in {out}; --resume continues")
            _exit_interrupted()
    table = write_study_table(rows, out)
    unsafe = [r for r in rows if r["metrics"].get("within_exempt_group") is False]
    if unsafe:
        err.print(
            f"[bold red]warning:[/] {len(unsafe)} runs exceed an IEC 62471 exempt-group limit",
            highlight=False,
        )
    flagged = [r for r in rows if r["metrics"].get("non_finite")]
    if flagged:
        err.print(
            f"[yellow]warning:[/] {len(flagged)} runs have a metric that is not a finite number "
            f"(e.g. run {flagged[0]['index']}: {', '.join(flagged[0]['metrics']['non_finite'])}); "
            "stored as null, listed under non_finite",
            highlight=False,
        )
    err.print(f"{len(rows)}/{total} runs in {out / 'results.sqlite'}; table in {table}")


def _check_executor(workers: int | None, dask: str | None, lock_timeout: float) -> None:
    """The executor options of ``study`` and ``dataset``."""
    if workers is not None and workers < 1:
        _fail(f"--workers {workers}: must be ≥ 1")
    if workers is not None and dask not in (None, "local"):
        _fail(
            f"--workers {workers} with --dask {dask}: a scheduler's cluster has its own workers "
            "(--workers sizes --dask local or the process pool)"
        )
    if not 0 <= lock_timeout <= 86400:
        _fail(f"--lock-timeout {lock_timeout}: must be 0 to 86400 s")
    from eyelume.optimize.runner import check_scheduler

    check_scheduler(dask)  # a malformed address or none answering: one line, in seconds


@app.command()
def dataset(
    dataset_file: Annotated[Path, typer.Argument(help="The dataset file (TOML).")],
    out: Annotated[Path, typer.Option("--out", help="The dataset's folder (created).")],
    resume: ResumeOpt = False,
    workers: WorkersOpt = None,
    dask: DaskOpt = None,
    lock_timeout: LockTimeoutOpt = 60.0,
) -> None:
    """Make a labelled dataset of eye pictures: the sensor's picture (PNG), the irradiance
    (.npy) and one label line each (labels.jsonl), every picture committed at once to
    OUT/results.sqlite (resumable: --resume makes the missing ones, the same bytes)."""
    from eyelume.optimize.dataset import check_out, load_dataset, run_dataset

    _check_executor(workers, dask, lock_timeout)
    ds = load_dataset(dataset_file)
    _check_out(out)
    check_out(ds, out, resume)  # not empty, or another dataset's: one line, before any render
    if (Path(out) / "results.sqlite").exists():
        from eyelume.optimize.store import check_store

        check_store(out)  # a damaged store is one line before the banner, not after it
    err.print(
        f"dataset {ds.name}: {ds.pictures} pictures into {out} "
        "(Ctrl-C, then --resume, loses nothing)"
    )
    if dask in (None, "local"):
        # the workers share this machine's Numba cache: compile the kernels here once, saying
        # so on a fresh machine (a minute of silence otherwise), and they load them from it
        from eyelume.compile import compile_scene
        from eyelume.optimize.dataset import bases

        _warm_up(compile_scene(bases(ds).base))
    with _progress_bar("[bold]pictures", "{task.completed}/{task.total}") as bar:
        task = bar.add_task("dataset", total=ds.pictures)
        first = [True]

        def progress(done: int, total: int) -> None:
            if first[0]:  # pictures already done: the ETA counts from here, not from 0
                first[0] = False
                bar.reset(task, total=total, completed=done)
            else:
                bar.update(task, completed=done)

        try:
            done = run_dataset(
                ds,
                out,
                workers,
                resume,
                progress,
                dask,
                lock_timeout_s=lock_timeout,
                note=lambda msg: err.print(f"[yellow]{msg}[/]", highlight=False),
            )
        except OSError as exc:  # a full disk, a folder made read-only meanwhile
            bar.stop()
            _fail(f"--out {out}: {exc}; the finished pictures are kept: --resume continues")
        except KeyboardInterrupt:
            bar.stop()
            err.print(f"interrupted: the finished pictures are in {out}; --resume continues")
            _exit_interrupted()
    err.print(f"{done}/{ds.pictures} pictures in {out}; labels in {out / 'labels.jsonl'}")


@app.command()
def report(
    folder: Annotated[
        Path,
        typer.Argument(help="A study's folder (its results.sqlite) or a dataset's (labels.jsonl)."),
    ],
    scene: Annotated[
        str | None,
        typer.Option(
            help="The study's base scene: evaluate the best run anew (eye-plane pattern, eye "
            "image, tracking errors) and store it in FOLDER first (default: skip)."
        ),
    ] = None,
    out: Annotated[
        Path | None,
        typer.Option("--out", help="The page to write (default: FOLDER/report.html)."),
    ] = None,
) -> None:
    """Write FOLDER/report.html (or --out). A dataset's folder (eyelume dataset): its label
    summary, a contact sheet of labelled pictures and the varied parameters' distributions. A
    study's: the study's table (unsafe runs in red), merit
    landscapes, the best runs and the best run's stored eye-plane pattern and eye image (--scene
    stores them). Reads the store read-only: a study still running is reported as far as it has
    committed; a read-only FOLDER needs --out (and no --scene)."""
    from eyelume.report.html import check_report_folder, write_report

    check_report_folder(folder)  # missing, a file, a render's or no kind: one line first
    if out is not None:
        if out.is_dir():
            _fail(f"--out {out}: is a folder; give the page's file name, e.g. {out}/report.html")
        _check_out(out.parent)
    if scene is not None and (folder / "labels.jsonl").exists():
        _fail(f"--scene {scene}: {folder} is a dataset's folder (labels.jsonl), not a study's")
    if scene is not None and folder.is_dir():
        # --scene stores the best run in FOLDER: a read-only folder is refused before the work
        _check_out(folder, option="--scene stores the best run in")
    try:
        if scene is not None:
            from eyelume.optimize.best_run import save_best_run

            err.print(f"evaluating the best run of {folder} on {scene}")
            save_best_run(folder, scene)
        path = write_report(folder, out)
    except (OSError, ValueError) as exc:
        _fail(str(exc))
    err.print(f"wrote {path}")


@app.command("dataset-export")
def dataset_export(
    folder: Annotated[Path, typer.Argument(help="A dataset folder (eyelume dataset's --out).")],
    out: Annotated[Path, typer.Option("--out", help="The folder to write the copy into.")],
    to: Annotated[
        str, typer.Option("--to", help="The layout: openeds (the only one).")
    ] = "openeds",
    split: Annotated[
        str, typer.Option(help="The split folder written (OpenEDS: train, validation, test).")
    ] = "train",  # fmt: skip
    size: Annotated[
        str,
        typer.Option(
            help="COLSxROWS canvas the pictures are fitted onto (aspect kept, black "
            "padding), or 'native' to keep each picture's size."
        ),  # fmt: skip
    ] = "640x400",
) -> None:
    """Copy a labelled dataset into the layout an OpenEDS-trained segmentation model reads:
    OUT/SPLIT/images/NNNNNN.png (8-bit grey, 640 × 400 by default) and OUT/SPLIT/labels/
    NNNNNN.npy (uint8 ids 0 background, 1 sclera, 2 iris, 3 pupil), with OUT/eyelume_export.json
    mapping each picture's pixels to the label file's (eyelume.report.dataset_outputs)."""
    from eyelume.report.dataset_outputs import export_openeds

    if to != "openeds":
        _fail(f"--to {to!r}: the only layout is 'openeds'")
    if size == "native":
        canvas = None
    else:
        try:
            canvas = tuple(int(v) for v in size.lower().split("x"))
        except ValueError:
            canvas = ()
        if len(canvas) != 2 or min(canvas) < 1:
            _fail(f"--size {size!r}: give COLSxROWS (e.g. 640x400) or 'native'")
    if not folder.is_dir():
        _fail(f"{folder}: is not a folder (a dataset folder written by eyelume dataset)")
    _check_out(out)
    with _progress_bar("[bold]export[/] {task.description}", "{task.completed}/{task.total} "
                       "pictures") as bar:  # fmt: skip
        task = bar.add_task("", total=None)
        summary = export_openeds(
            folder, out, split=split, size=canvas,
            progress=lambda done, total: bar.update(task, completed=done, total=total),
        )  # fmt: skip
    shares = ", ".join(f"{k} {v}" for k, v in summary.class_pixels.items())
    err.print(
        f"wrote {summary.pictures} pictures to {out / split} (OpenEDS layout; label pixels by "
        f"class id: {shares}); pixel mapping in {out / 'eyelume_export.json'}",
        highlight=False,
        soft_wrap=True,
    )


@app.command()
def info(
    scene: SceneOpt = "paper2005",
    set_: SetOpt = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON.")] = False,
) -> None:
    """Print the derived optics: lens EFL, image distance, magnification, F-numbers, eye power,
    glass indices — as indented ``name: value`` lines to read, or with --json as one JSON
    object (the same numbers, full precision) for a program."""
    from eyelume.info import info_text, scene_info
    from eyelume.json_files import dumps

    sc = _load(scene, set_)
    data = scene_info(sc)
    out_stream.write((dumps(data) if as_json else info_text(data)) + "\n")
