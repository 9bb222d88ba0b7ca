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
    rays: Annotated[
        int | None, typer.Option(help="Rays to trace (default: the scene's run.rays).")
    ] = None,
    seed: Annotated[
        int | None, typer.Option(help="Random seed (default: the scene's run.seed).")
    ] = None,
    set_: SetOpt = None,
) -> None:
    """Trace a scene (forward Monte Carlo) and write the eye image, eye-plane irradiance,
    pictures, layout and power ledger into OUT."""
    from eyelume.compile import compile_scene
    from eyelume.render import render as render_scene
    from eyelume.report.outputs import write_render_outputs

    sc = _load(scene, set_)
    if rays is not None and rays < 1:
        _fail(f"--rays {rays}: must be ≥ 1")
    if seed is not None and seed < 0:
        _fail(f"--seed {seed}: must be ≥ 0")
    try:
        cs = compile_scene(sc)
    except (SceneError, GlassError) as exc:
        _fail(str(exc))
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
            cs, rays=rays, seed=seed, progress=lambda d, t: bar.update(task, completed=d)
        )
    if result.interrupted:
        err.print(f"interrupted: writing the {result.rays:,} rays traced so far")
    written = write_render_outputs(result, cs, out)
    p = result.summary()["power_w"]
    err.print(
        f"{result.rays:,} rays in {result.wall_time_s:.2f} s; emitted {p['emitted']:.4g} W, "
        f"on the sensor {p['sensor']:.3g} W; wrote {len(written)} files to {out}"
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
