"""The ``eyelume`` command line (Typer). Thin: parses, calls the API, prints; no physics here.

Every error a user can cause ends with a one-line message on stderr and exit code 2.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from eyelume.scene.glass import GlassError
from eyelume.scene.io import SceneError, load_scene

app = typer.Typer(
    add_completion=False,
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    help="Design the near-infrared illumination of an eye tracker in a head-mounted display.",
)
err = Console(stderr=True)

SceneOpt = Annotated[
    str, typer.Option("--scene", help="A preset name (paper2005) or a scene TOML file.")
]
SetOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--set", help="Override a scene field by its dotted path: key=value (repeatable)."
    ),
]


def _fail(message: str) -> None:
    err.print(f"[bold red]error:[/] {message}", highlight=False, soft_wrap=True)
    raise typer.Exit(2)


def _overrides(pairs: list[str] | None) -> dict[str, str]:
    out = {}
    for pair in pairs or []:
        key, sep, value = pair.partition("=")
        if not sep or not key.strip():
            _fail(f"--set {pair!r}: expected key=value, e.g. leds.height_mm=40")
        out[key.strip()] = value.strip()
    return out


def _load(scene: str, sets: list[str] | None):
    try:
        return load_scene(scene, _overrides(sets))
    except SceneError as exc:
        _fail(str(exc))


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
    seed: Annotated[
        int | None, typer.Option(help="Random seed (default: the scene's run.seed).")
    ] = None,
    set_: SetOpt = None,
) -> None:
    """Render a scene and write the eye image (irradiance, its noise, the camera's digital
    reading), the eye-plane irradiance, pictures, layout and summary into OUT."""
    from eyelume.compile import compile_scene
    from eyelume.render import render as render_scene
    from eyelume.report.outputs import write_render_outputs

    sc = _load(scene, set_)
    estimator = estimator or ("forward" if rays is not None else sc.run.estimator)
    if estimator not in ("fast", "forward"):
        _fail(f"--estimator {estimator!r}: must be 'fast' or 'forward'")
    if rays is not None and (rays < 1 or estimator != "forward"):
        _fail(f"--rays {rays}: must be ≥ 1, with --estimator forward (fast: --samples)")
    if samples is not None and (samples < 1 or estimator != "fast"):
        _fail(f"--samples {samples}: must be ≥ 1, with --estimator fast (forward: --rays)")
    if rel_error is not None and (not 0 < rel_error < 1 or estimator != "fast"):
        _fail(f"--rel-error {rel_error}: must be in (0, 1), with --estimator fast")
    if seed is not None and seed < 0:
        _fail(f"--seed {seed}: must be ≥ 0")
    try:
        cs = compile_scene(sc)
    except (SceneError, GlassError) as exc:
        _fail(str(exc))
    if estimator == "fast":
        goal = (
            f"to a {rel_error:.2%} relative error in the median skin pixel"
            if rel_error is not None
            else f"{samples or sc.run.samples_per_pixel} samples per pixel"
        )
        err.print(f"rendering {sc.name} (fast estimator, {goal}; Ctrl-C stops after a round)")
        with err.status("rendering") as spinner:
            result = render_scene(
                cs,
                seed=seed,
                estimator="fast",
                samples_per_pixel=samples,
                rel_error=rel_error,
                status=lambda msg: spinner.update(f"rendering: {msg}"),
            )
    else:
        total = sc.run.rays if rays is None else rays
        err.print(f"tracing {total:,} rays of {sc.name} (Ctrl-C stops after the current batch)")
        with Progress(
            TextColumn("[bold]tracing"),
            BarColumn(),
            TextColumn("{task.completed:,}/{task.total:,} rays"),
            TimeElapsedColumn(),
            TimeRemainingColumn(),
            console=err,
            transient=True,
        ) as bar:
            task = bar.add_task("trace", total=total)
            result = render_scene(
                cs,
                rays=rays,
                seed=seed,
                estimator="forward",
                progress=lambda d, t: bar.update(task, completed=d),
            )
    if result.interrupted:
        err.print(f"interrupted: writing the {result.rays:,} rays traced so far")
    written = write_render_outputs(result, cs, out)
    summary = result.summary()
    skin = summary["regions"].get("skin", {})
    noise = (
        f"; median skin pixel ±{skin['median_pixel_rel_error']:.2%}" if skin.get("pixels") else ""
    )
    err.print(
        f"{result.rays:,} rays in {result.wall_time_s:.2f} s ({result.estimator}){noise}; "
        f"on the sensor {summary['power_w']['sensor']:.3g} W of "
        f"{summary['power_w']['emitted']:.4g} W emitted; wrote {len(written)} files to {out}"
    )
    if result.interrupted:
        raise typer.Exit(130)


@app.command()
def info(
    scene: SceneOpt = "paper2005",
    set_: SetOpt = None,
    as_json: Annotated[bool, typer.Option("--json", help="Print JSON.")] = False,
) -> None:
    """Print the derived optics: lens EFL, image distance, magnification, F-numbers, eye power,
    glass indices."""
    from eyelume.info import scene_info

    sc = _load(scene, set_)
    try:
        data = scene_info(sc)
    except (SceneError, GlassError) as exc:
        _fail(str(exc))
    if as_json:
        sys.stdout.write(json.dumps(data, indent=2) + "\n")
        return
    Console().print_json(data=data)
