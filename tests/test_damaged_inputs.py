"""Damaged input files through the real entry point, property-based (issue 12).

Hypothesis makes scene TOML files, LED profile CSVs and AGF glass catalogs, damages them
(truncation, wrong types, NaN and infinities, huge and tiny values, other encodings, stray
bytes, renamed keys, glasses named twice) and runs ``eyelume info --scene FILE --json`` in
process; and, end to end, damaged scene files through ``eyelume render`` (a tiny picture and
budget), damaged study files through ``eyelume study``, and damaged pictures (PNG, TIFF,
``.npy``) through ``eyelume track``. Every case must end in one of two ways:

* exit 0 with a finite result — strict JSON whose numbers are all finite (null allowed) on
  stdout (``info``, ``track``) or in the outputs (``render``'s ``summary.json``, ``study``'s
  table and store), or
* exit 2 with exactly one line on stderr, ``error: …``, naming a file or a field —

never a traceback, another exit code, or a hang: each case runs under an alarm (a warm
``info`` case takes ~0.2 s). The examples are derandomized (a fixed sequence: CI is
deterministic); the render and study cases, seconds each, are marked slow.
"""

from __future__ import annotations

import contextlib
import json
import math
import re
import signal
import tempfile
from pathlib import Path

import pytest
import tomli_w
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

import eyelume
from eyelume.cli import app

CASE_SECONDS = 20
SETTINGS = settings(
    max_examples=40,
    deadline=None,  # the alarm below bounds each case; the first one compiles the kernels
    derandomize=True,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

BASE = eyelume.load_scene("paper2005").model_dump(mode="python")


def _toml(data: dict) -> str:
    def ready(v):
        if isinstance(v, dict):
            return {k: ready(x) for k, x in v.items() if x is not None}
        if isinstance(v, list | tuple):
            return [ready(x) for x in v]
        return v

    return tomli_w.dumps(ready(data))


class CaseHang(BaseException):
    """A case that ran over its time: a BaseException, so that no ``except Exception`` (nor
    the commands' ``except OSError``) can turn a hang into a clean-looking exit."""


@contextlib.contextmanager
def _alarm(seconds: int):
    def fire(signum, frame):
        raise CaseHang(f"a case ran over {seconds} s")

    old = signal.signal(signal.SIGALRM, fire)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def _finite_numbers(value) -> bool:
    if isinstance(value, dict):
        return all(_finite_numbers(v) for v in value.values())
    if isinstance(value, list):
        return all(_finite_numbers(v) for v in value)
    if isinstance(value, float):
        return math.isfinite(value)
    return True


def _strict(text: str):
    def refuse(token):
        raise ValueError(f"non-JSON token {token}")

    return json.loads(text, parse_constant=refuse)


_FIELD = re.compile(r"[a-z_]+\.[a-z0-9_]+")


def run_command(folder: Path, args: list[str], seconds: int = CASE_SECONDS):
    """``eyelume ARGS`` in process under an alarm; the result when it exits 0, else None after
    checking the one allowed failure: exit 2 with one line ``error: …`` naming a file (in
    ``folder``) or a field — never a traceback, another exit code or a hang."""
    with _alarm(seconds):
        res = CliRunner().invoke(app, args)
    assert "Traceback" not in res.output
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        raise AssertionError(f"uncaught {type(res.exception).__name__}") from res.exception
    if res.exit_code == 0:
        return res
    assert res.exit_code == 2, (res.exit_code, res.output)
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    errors = [ln for ln in lines if ln.startswith("error:")]
    assert len(errors) == 1 and lines[-1] == errors[0], res.stderr
    msg = " ".join(errors[0].split())
    names_option = re.search(r"--[a-z]", msg)
    assert str(folder) in msg or "field" in msg or _FIELD.search(msg) or names_option, msg
    return None


def run_info(folder: Path, scene_file: Path) -> None:
    """``eyelume info --scene FILE --json`` and the two allowed outcomes (module docstring)."""
    res = run_command(folder, ["info", "--scene", str(scene_file), "--json"])
    if res is not None:
        data = _strict(res.stdout)
        assert _finite_numbers(data)


# --- damage ------------------------------------------------------------------------------------

BAD_VALUES = [
    "nan", "inf", "-inf", "1e308", "-1e308", "1e999", "0", "-1", "1e-320", "0.0",
    '"x"', "true", "[]", "{}", '"nan"', "12345678901234567890",
]  # fmt: skip
ENCODINGS = ["utf-8", "utf-8-sig", "utf-16", "utf-16-be", "utf-16-le", "cp1252"]
NUMBER = re.compile(r"(?<![\w.\"'])-?\d+(\.\d+)?([eE][+-]?\d+)?(?![\w.])")


@st.composite
def damaged_text(draw, text: str) -> bytes:
    """``text`` with 1-3 kinds of damage, as bytes in a drawn encoding."""
    kinds = draw(st.lists(st.sampled_from(["value", "key", "truncate", "bytes"]), max_size=3))
    for kind in kinds:
        if kind == "value":
            spots = list(NUMBER.finditer(text))
            if spots:
                m = spots[draw(st.integers(0, len(spots) - 1))]
                text = text[: m.start()] + draw(st.sampled_from(BAD_VALUES)) + text[m.end() :]
        elif kind == "key":
            keys = list(re.finditer(r"^(\w+) =", text, flags=re.M))
            if keys:
                m = keys[draw(st.integers(0, len(keys) - 1))]
                text = text[: m.start(1)] + m.group(1) + "x" + text[m.end(1) :]
        elif kind == "truncate":
            text = text[: draw(st.integers(0, len(text)))]
    data = text.encode(draw(st.sampled_from(ENCODINGS)), errors="replace")
    if "bytes" in kinds:
        at = draw(st.integers(0, len(data)))
        data = data[:at] + draw(st.binary(min_size=1, max_size=8)) + data[at:]
    return data


# --- scene files -------------------------------------------------------------------------------


@SETTINGS
@given(st.data())
def test_damaged_scene_files(data):
    text = "# a user's scene, 20 °C\n" + _toml(BASE)
    raw = data.draw(damaged_text(text))
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        (folder / "scene.toml").write_bytes(raw)
        run_info(folder, folder / "scene.toml")


# --- LED profile tables ------------------------------------------------------------------------


@st.composite
def profile_csv(draw) -> str:
    n = draw(st.integers(2, 12))
    steps = draw(st.lists(st.floats(0.5, 20.0), min_size=n - 1, max_size=n - 1))
    angles = [0.0]
    for s in steps:
        angles.append(min(angles[-1] + s, 90.0))
    values = sorted(draw(st.lists(st.floats(0.0, 1.0), min_size=n, max_size=n)), reverse=True)
    if draw(st.booleans()):
        values[-1] = 0.0
    rows = [f"{a:g},{v:g}" for a, v in zip(angles, values, strict=True)]
    header = draw(st.sampled_from(["", "Angle (°),Relative intensity\n", "# datasheet\n"]))
    return header + "\n".join(rows) + "\n"


@pytest.mark.slow
@SETTINGS
@given(st.data())
def test_damaged_led_profile_tables(data):
    raw = data.draw(damaged_text(data.draw(profile_csv())))
    scene = dict(BASE, leds=dict(BASE["leds"], profile={"kind": "table", "table_csv": "led.csv"}))
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        (folder / "led.csv").write_bytes(raw)
        (folder / "scene.toml").write_text(_toml(scene), encoding="utf-8")
        run_info(folder, folder / "scene.toml")


# --- glass catalogs ----------------------------------------------------------------------------

NBK7 = (1.03961212, 0.00600069867, 0.231792344, 0.0200179144, 1.01046945, 103.560653)


@st.composite
def agf_catalog(draw) -> tuple[str, str]:
    """An AGF text of 1-3 glasses near N-BK7 (Sellmeier 1) and the name of its first."""
    lines = ["CC generated catalog"]
    names = []
    for i in range(draw(st.integers(1, 3))):
        name = draw(st.sampled_from([f"G{i}", "G0", "N-BK7"]))
        names.append(name)
        scale = draw(st.floats(0.5, 1.5))
        cd = [c * scale if k % 2 == 0 else c for k, c in enumerate(NBK7)]
        cd_text = " ".join(f"{c:.9g}" for c in cd)
        if draw(st.booleans()):  # a vendor's continuation lines
            cd_text = (
                " ".join(f"{c:.9g}" for c in cd[:3]) + "\n  " + " ".join(f"{c:.9g}" for c in cd[3:])
            )
        nd = draw(st.sampled_from(["1.5168", "1.6", "1.4"]))
        lines += [
            f"NM {name} 2 517642.251 {nd} 64.17 0 1 0",
            f"CD {cd_text} 0 0 0 0",
            draw(st.sampled_from(["LD 0.3 2.5", "LD 0 0", "LD 2.5 0.3", ""])),
        ]
    return "\n".join(ln for ln in lines if ln) + "\n", names[0]


@SETTINGS
@given(st.data())
def test_damaged_glass_catalogs(data):
    text, first = data.draw(agf_catalog())
    raw = data.draw(damaged_text(text))
    lens = dict(BASE["lens"], glass_catalogs=["cat.agf"])
    lens["surfaces"] = [dict(s) for s in lens["surfaces"]]
    lens["surfaces"][0]["glass"] = first
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        (folder / "cat.agf").write_bytes(raw)
        (folder / "scene.toml").write_text(_toml(dict(BASE, lens=lens)), encoding="utf-8")
        run_info(folder, folder / "scene.toml")


@pytest.mark.parametrize(
    "raw",
    [b"", b"\xff\xfe", b"\x00" * 64, 'name = "x"\n[eye]\n'.encode("utf-16")],
    ids=["empty", "BOM only", "NULs", "UTF-16 without the required fields"],
)
def test_degenerate_scene_files(tmp_path, raw):
    (tmp_path / "scene.toml").write_bytes(raw)
    run_info(tmp_path, tmp_path / "scene.toml")


# --- end to end: render, study, track ----------------------------------------------------------

#: A tiny render: 12 × 9 pixels, 8 samples per pixel (two 2 × 2 sets), fast estimator.
TINY = dict(
    BASE,
    sensor=dict(BASE["sensor"], cols=12, rows=9),
    run=dict(BASE["run"], estimator="fast", samples_per_pixel=8),
)


@pytest.fixture(scope="module")
def kernels():
    """The fast kernels compiled (or loaded) once, outside the cases' alarms: a first
    compilation takes about a minute and is no hang."""
    from eyelume.compile import compile_scene
    from eyelume.estimators.fast_run import warm_up
    from eyelume.scene.io import validate_scene

    warm_up(compile_scene(validate_scene(TINY)))


@pytest.mark.slow
@settings(SETTINGS, max_examples=12)
@given(st.data())
def test_damaged_scene_files_render(kernels, data):
    raw = data.draw(damaged_text("# a user's scene\n" + _toml(TINY)))
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        (folder / "scene.toml").write_bytes(raw)
        out = folder / "out"
        res = run_command(folder, ["render", "--scene", str(folder / "scene.toml"),
                                   "--out", str(out)], seconds=60)  # fmt: skip
        if res is not None:
            summary = _strict((out / "summary.json").read_text(encoding="utf-8"))
            assert summary["power_w"]["sensor"] is not None
            assert _finite_numbers(summary)


STUDY = """name = "damaged"
scene = "scene.toml"
seed = 1
metrics = ["safety", "eye_plane_merit"]
delta = 0.3
[[vary]]
path = "leds.height_mm"
grid = [20.0, 40.0, 2]
[[vary]]
path = "leds.pitch_deg"
values = [0, 20]
"""


@pytest.mark.slow
@settings(SETTINGS, max_examples=12)
@given(st.data())
def test_damaged_study_files(kernels, data):
    raw = data.draw(damaged_text(STUDY))
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        (folder / "scene.toml").write_text(_toml(TINY), encoding="utf-8")
        (folder / "study.toml").write_bytes(raw)
        out = folder / "out"
        res = run_command(folder, ["study", str(folder / "study.toml"), "--out", str(out),
                                   "--workers", "1"], seconds=120)  # fmt: skip
        if res is None:
            assert not (out / "results.sqlite").exists()  # refused before the store
            return
        rows = (out / "table.csv").read_text(encoding="utf-8").splitlines()
        assert len(rows) >= 2
        assert "nan" not in "".join(rows[1:]).lower() and "inf" not in "".join(rows[1:]).lower()


@st.composite
def picture_bytes(draw) -> tuple[str, bytes]:
    """A small grey picture as a camera or eyelume writes it (8/16-bit PNG, TIFF, float .npy
    with NaN pixels), then damaged: truncated, stray bytes, or left whole."""
    import io

    import cv2
    import numpy as np

    rows, cols = draw(st.integers(1, 40)), draw(st.integers(1, 40))
    rng = np.random.default_rng(draw(st.integers(0, 2**16)))
    kind = draw(st.sampled_from(["png8", "png16", "tif", "npy"]))
    if kind == "npy":
        img = rng.normal(100.0, 30.0, (rows, cols))
        img[rng.random((rows, cols)) < draw(st.floats(0.0, 1.0))] = np.nan
        buf = io.BytesIO()
        np.save(buf, img.astype(draw(st.sampled_from(["float32", "float64"]))))
        data, suffix = buf.getvalue(), ".npy"
    else:
        depth = np.uint16 if kind == "png16" else np.uint8
        img = rng.integers(0, np.iinfo(depth).max, (rows, cols)).astype(depth)
        suffix = ".tif" if kind == "tif" else ".png"
        data = cv2.imencode(suffix, img)[1].tobytes()
    damage = draw(st.sampled_from(["none", "truncate", "bytes"]))
    if damage == "truncate":
        data = data[: draw(st.integers(0, len(data)))]
    elif damage == "bytes":
        at = draw(st.integers(0, len(data)))
        data = data[:at] + draw(st.binary(min_size=1, max_size=16)) + data[at:]
    return suffix, data


@SETTINGS
@given(st.data())
def test_damaged_pictures_track(data):
    suffix, raw = data.draw(picture_bytes())
    leds = data.draw(st.sampled_from([[], ["--leds", "0,90,180,270"], ["--leds", "nan,90"]]))
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        (folder / f"eye{suffix}").write_bytes(raw)
        res = run_command(folder, ["track", str(folder / f"eye{suffix}"), *leds])
        if res is not None:
            assert _finite_numbers(_strict(res.stdout))


@pytest.mark.parametrize("encoding", ["utf-8-sig", "utf-16", "utf-16-be", "cp1252"])
def test_a_study_file_saved_in_another_encoding_loads(tmp_path, encoding):
    """Found by the damaged-study cases: a study file not in UTF-8 was a UnicodeDecodeError
    traceback; it is read as scene files are."""
    from eyelume.optimize.study import load_study, plan_runs

    text = "# °\n" + STUDY.replace('scene = "scene.toml"', 'scene = "paper2005"')
    (tmp_path / "study.toml").write_bytes(text.encode(encoding))
    assert len(plan_runs(load_study(tmp_path / "study.toml"))) == 4


@pytest.mark.parametrize(
    ("name", "content", "words"),
    [
        ("eye.npy", b"hello\n", "not a NumPy .npy file"),  # text named .npy
        ("eye.npy", b"\x89PNG\r\n\x1a\n" + bytes(32), "not a NumPy .npy file"),  # a PNG's start
        ("pictures", None, "a directory, not a picture file"),
    ],
)
def test_track_names_what_a_file_is_not(tmp_path, name, content, words):
    """A file named .npy that is not one: NumPy took it for a pickle and said so ("pickled
    (object) data … load it unsafely"), the wrong cause and an unsafe advice; a directory was
    "no such file" (a new user's findings, session 19)."""
    from typer.testing import CliRunner

    from eyelume.cli import app

    path = tmp_path / name
    if content is None:
        path.mkdir()
    else:
        path.write_bytes(content)
    res = CliRunner().invoke(app, ["track", str(path)])
    assert res.exit_code == 2, res.output
    text = " ".join(res.output.split())
    assert words in text and "pickle" not in text and "Traceback" not in res.output
    assert len(res.output.strip().splitlines()) == 1


@pytest.mark.parametrize("suffix", [".png", ".tif", ".jpg"])
def test_track_refuses_a_picture_cut_short_in_one_line(tmp_path, suffix):
    """A picture file cut in half: one line naming it on stderr, exit 2 — not OpenCV's
    [ERROR] lines before ours (TIFF; written by the C library, so the command runs in its own
    process here), nor a JPEG decoded with its missing half grey and analysed (libjpeg only
    printed "Premature end of JPEG file"; a new user's findings, session 19)."""
    import subprocess
    import sys

    import cv2
    import numpy as np

    img = (np.random.default_rng(0).random((100, 120)) * 255).astype(np.uint8)
    data = cv2.imencode(suffix, img)[1].tobytes()
    path = tmp_path / f"eye{suffix}"
    path.write_bytes(data[: len(data) // 2])
    code = "import sys; from eyelume.cli import app; sys.argv = ['eyelume', *sys.argv[1:]]; app()"
    res = subprocess.run([sys.executable, "-c", code, "track", str(path)],
                         capture_output=True, text=True, timeout=300)  # fmt: skip
    assert res.returncode == 2, (res.stdout, res.stderr)
    lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("error:") and f"eye{suffix}" in lines[0], lines
    assert res.stdout.strip() == ""
