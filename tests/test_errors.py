"""The error root: every kind formats one line naming the field or file and the value, is a
ValueError as before, and the command line reports any of them in one place (exit code 2)."""

from __future__ import annotations

import pytest
import typer
from typer.testing import CliRunner

from eyelume import cli, errors
from eyelume.errors import (
    BudgetError,
    EyelumeError,
    GeometryError,
    GlassError,
    InputFileError,
    OptionError,
    SceneError,
    StoreError,
)
from eyelume.optimize.store import StoreBusy

KINDS = [
    SceneError,
    InputFileError,
    GlassError,
    GeometryError,
    BudgetError,
    StoreError,
    OptionError,
]


@pytest.mark.parametrize("kind", KINDS)
def test_every_kind_is_an_eyelume_error_and_a_value_error(kind):
    exc = kind("must be > 0", file="a.toml", field="leds.height_mm", value=-3.0)
    assert isinstance(exc, EyelumeError) and isinstance(exc, ValueError)
    assert str(exc) == "a.toml: field 'leds.height_mm' = -3.0: must be > 0"
    assert (exc.file, exc.field, exc.value) == ("a.toml", "leds.height_mm", -3.0)


def test_the_line_leaves_out_what_is_not_given():
    assert str(SceneError("unknown field", file="scene", field="leds.x")) == (
        "scene: field 'leds.x': unknown field"
    )
    assert str(InputFileError("row 3 is empty", file="p.csv")) == "p.csv: row 3 is empty"
    assert str(BudgetError("too large", value=10**7)) == "value 10000000: too large"
    assert str(GeometryError("an LED lies inside the cornea")) == "an LED lies inside the cornea"
    # a value that is None is still named
    assert str(SceneError("is required", field="x", value=None)) == "field 'x' = None: is required"


def test_the_line_is_always_one_line():
    exc = InputFileError("bad\nrecord\r\n  here", file="cat.agf")
    assert str(exc) == "cat.agf: bad record here"


def test_store_busy_is_a_store_error_and_still_a_runtime_error():
    exc = StoreBusy("out: another study is writing here")
    assert isinstance(exc, StoreError) and isinstance(exc, RuntimeError)


def test_every_public_error_class_is_listed():
    listed = set(errors.__all__)
    defined = {
        n
        for n, v in vars(errors).items()
        if isinstance(v, type) and issubclass(v, Exception) and not n.startswith("_")
    }
    assert defined == listed


@pytest.mark.parametrize("kind", KINDS)
def test_cli_reports_any_kind_in_one_place(kind, monkeypatch):
    """A command that raises any EyelumeError ends with one line and exit code 2, no traceback."""

    def boom(scene: str = "paper2005", set_=None, as_json: bool = False) -> None:
        raise kind("is not a number", file="x.toml", field="eye.gaze_deg", value="abc")

    import eyelume.info

    monkeypatch.setattr(eyelume.info, "scene_info", lambda sc: boom())
    res = CliRunner().invoke(cli.app, ["info"])
    assert res.exit_code == 2, res.output
    assert res.exception is None or isinstance(res.exception, SystemExit)
    lines = [ln for ln in res.output.splitlines() if ln.strip()]
    assert lines == ["error: x.toml: field 'eye.gaze_deg' = 'abc': is not a number"]


def test_cli_option_error_and_markup_in_values_print_verbatim():
    res = CliRunner().invoke(cli.app, ["info", "--set", "[bold]x"])
    assert res.exit_code == 2
    assert res.output.strip() == (
        "error: --set '[bold]x': expected key=value, e.g. leds.height_mm=40"
    )


def test_fail_raises_an_option_error():
    with pytest.raises(OptionError, match="--seed -1"):
        cli._fail("--seed -1: must be ≥ 0")
    assert not issubclass(OptionError, typer.Exit)


def test_the_cli_catches_the_error_root_in_one_place():
    """pbrt-v4's main: errors surface to the top; one handler prints them. No command catches
    the root or one of its kinds itself (it may turn a foreign ValueError or OSError into one)."""
    import ast
    import inspect

    ours = {*errors.__all__, "StoreBusy"}
    tree = ast.parse(inspect.getsource(cli))
    caught = [
        ast.unparse(h.type)
        for h in ast.walk(tree)
        if isinstance(h, ast.ExceptHandler)
        and h.type is not None
        and any(isinstance(n, ast.Name) and n.id in ours for n in ast.walk(h.type))
    ]
    assert caught == ["EyelumeError"]
