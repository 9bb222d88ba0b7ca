"""The tools hold the line: every per-file allowance in pyproject.toml is still needed (a file
that no longer exceeds a limit loses its allowance, so it cannot grow back unnoticed), and no
extra installs a second OpenCV build over the headless one."""

from __future__ import annotations

import json
import shutil
import subprocess
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
LIMITS = ("C901", "PLR0912", "PLR0913", "PLR0915")


def _allowances() -> dict[str, list[str]]:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    ignores = config["tool"]["ruff"]["lint"]["per-file-ignores"]
    return {k: [c for c in v if c in LIMITS] for k, v in ignores.items()}


def _violations(paths: list[Path]) -> set[tuple[str, str]]:
    """(file relative to the repository, rule) of every limit the files exceed, no allowance."""
    ruff = shutil.which("ruff")
    if ruff is None:
        pytest.fail("ruff is not installed (it comes with the test extra)")
    out = subprocess.run(
        [ruff, "check", "--select", ",".join(LIMITS), "--config", "lint.per-file-ignores = {}",
         "--output-format", "json", "--exit-zero", *map(str, paths)],
        cwd=ROOT, capture_output=True, text=True, check=True, timeout=120,
    ).stdout  # fmt: skip
    return {(Path(v["filename"]).relative_to(ROOT).as_posix(), v["code"]) for v in json.loads(out)}


def test_every_allowance_is_still_needed():
    allowances = _allowances()
    assert allowances, "pyproject.toml lists no per-file allowance"
    files = {p: sorted(ROOT.glob(p)) for p in allowances}
    found = _violations([f for fs in files.values() for f in fs])
    stale = []
    for pattern, codes in allowances.items():
        names = {f.relative_to(ROOT).as_posix() for f in files[pattern]}
        assert names, f"{pattern}: matches no file"
        for code in codes:
            if not any((name, code) in found for name in names):
                stale.append(f"{pattern}: {code}")
    assert not stale, f"allowances no longer needed, remove them from pyproject.toml: {stale}"


#: Distributions that put a second ``cv2`` package beside ``opencv-python-headless`` (the same
#: folder: uninstalling or upgrading one breaks the other): OpenCV's other builds, and
#: ``pupil-detectors``, whose metadata requires ``opencv-python`` (install it with --no-deps).
SECOND_CV2 = {"opencv-python", "opencv-contrib-python", "opencv-contrib-python-headless"}
SECOND_CV2 |= {"pupil-detectors"}


def test_no_extra_installs_a_second_opencv():
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    project = config["project"]
    reqs = {"(core)": project["dependencies"], **project["optional-dependencies"]}
    bad = {}
    for extra, items in reqs.items():
        for r in items:
            name = r.split(";")[0].split("[")[0]
            for sep in "<>=!~ ":
                name = name.split(sep)[0]
            if name.strip().lower().replace("_", "-") in SECOND_CV2:
                bad.setdefault(extra, []).append(r)
    assert not bad, f"these extras would install a second cv2 over the headless build: {bad}"
