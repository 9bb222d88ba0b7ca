"""The command line's messages: warnings one line each, once per command; usage errors (a
missing, unknown or badly typed option) one line naming the command, exit 2 (issue 12)."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

import eyelume
from eyelume.cli import app
from eyelume.scene.glass import SHIPPED_CATALOG

runner = CliRunner()


def test_catalog_warning_is_one_line_and_the_command_goes_on(tmp_path):
    """A glass named twice in a user's catalog: one 'warning:' line naming file and line, the
    first definition used, exit 0."""
    cat = tmp_path / "mine.agf"
    nbk7 = (
        "NM N-BK7 2 517642.251 1.5168 64.17 0 1 0\n"
        "CD 1.03961212 0.00600069867 0.231792344 0.0200179144 1.01046945 103.560653\n"
        "LD 0.3 2.5\n"
    )
    cat.write_text(nbk7 + nbk7.replace("1.03961212", "1.2"), encoding="utf-8")
    scene = eyelume.load_scene(
        "paper2005", {"lens.glass_catalogs": [str(cat), str(SHIPPED_CATALOG)]}
    )
    path = tmp_path / "scene.toml"
    eyelume.save_scene(scene, path)
    res = runner.invoke(app, ["info", "--scene", str(path), "--json"])
    assert res.exit_code == 0, res.output
    warnings = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(warnings) == 1, res.stderr
    assert warnings[0].startswith("warning:") and "mine.agf: line 4" in warnings[0]
    assert "'N-BK7' already defined on line 1" in warnings[0]


@pytest.mark.parametrize(
    ("args", "command", "says"),
    [
        (["render"], "eyelume render", "Missing option '--out'"),
        (["render", "--out", "x", "--bogus"], "eyelume render", "No such option: --bogus"),
        (["render", "--out", "x", "--samples", "abc"], "eyelume render", "'--samples'"),
        (["track"], "eyelume track", "Missing argument"),
        (["no-such-command"], "eyelume", "No such command 'no-such-command'"),
    ],
)
def test_usage_error_is_one_line_exit_2(args, command, says, tmp_path):
    """Click's usage errors come as one 'error:' line naming the command and the option, exit
    code 2, not Typer's framed box; nothing is written and no work starts."""
    res = runner.invoke(app, args, prog_name="eyelume")
    assert res.exit_code == 2, res.output
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1, res.stderr
    assert lines[0].startswith(f"error: {command}: ") and says in lines[0], lines[0]
    assert f"(see {command} --help)" in lines[0]
    assert res.stdout == ""
    assert not (tmp_path / "x").exists()


def test_help_still_exits_0():
    """--help, on the group and on a command, prints the help and exits 0."""
    for args in (["--help"], ["render", "--help"]):
        res = runner.invoke(app, args)
        assert res.exit_code == 0, res.output
        assert "Usage:" in res.stdout


def test_no_command_prints_the_help_and_no_empty_error_line():
    """``eyelume`` alone prints the help (exit 2, a usage error) and no empty 'error:' line."""
    res = runner.invoke(app, [], prog_name="eyelume")
    assert res.exit_code == 2
    assert "Usage:" in res.output
    assert "error:" not in res.output


def test_a_glass_used_outside_its_catalog_range_warns_once(tmp_path):
    """A glass whose catalog's LD range stops short of the scene's wavelength: its index is an
    extrapolation of its formula; one warning naming the first surface, the glass and the range
    (surfaces 3 and 6 are both made of it), and the command goes on (a fresh-user finding: only
    the JSON's wavelength_in_catalog_range said so)."""
    cat = tmp_path / "mine.agf"
    cat.write_text(
        "NM MYF5 2 603380.347 1.60342 38.03 0 0 0\n"
        "CD 1.3104463 0.00958633048 0.19603426 0.0457627627 0.96612977 115.011883 0 0 0 0\n"
        "LD 0.3126 0.5\n",
        encoding="utf-8",
    )
    scene = eyelume.load_scene(
        "paper2005",
        {
            "lens.glass_catalogs": [str(cat), str(SHIPPED_CATALOG)],
            "lens.surfaces.3.glass": "MYF5",
            "lens.surfaces.6.glass": "MYF5",
        },
    )
    path = tmp_path / "scene.toml"
    eyelume.save_scene(scene, path)
    res = runner.invoke(app, ["info", "--scene", str(path), "--json"])
    assert res.exit_code == 0, res.output
    warnings = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(warnings) == 1, res.stderr
    assert warnings[0].startswith("warning: lens.surfaces.3.glass = 'MYF5': 850 nm")
    assert "312.6–500 nm" in warnings[0] and "extrapolated" in warnings[0]
