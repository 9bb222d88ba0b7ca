"""Sunlight against the LEDs at 850 and at 940 nm (issue 15, part 3): the README's table.

Run from the repository root (~4 min on 2 cores)::

    python benchmarks/sunlight_850_940.py

Runs ``eyelume render`` twice on the see-through preset ``glasses-frame`` (fast estimator,
``--samples 2``, seed 0), the sun 40° above the headset's horizontal and 30° to the side
(``ambient.sun``, AM1.5 direct), the built-in QE curve, and a 40 nm band-pass filter about the
LEDs' wavelength: 830–870 nm with the scene (and its LEDs) at 850 nm, 920–960 nm at 940 nm (the
LEDs keep their radiant intensity). Prints each command and, from its ``summary.json``, the
sunlight through the filter, the glints' and the pupil's signal to ambient and the digital
picture's median; appends one JSON line to ``benchmarks/results/sunlight_850_940.jsonl``.
"""

from __future__ import annotations

import json
import os
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import _common as C  # noqa: E402

os.environ.setdefault("NUMBA_CACHE_DIR", str(C.WARM_CACHE))

COMMON = [
    "--scene", "glasses-frame", "--samples", "2", "--seed", "0",
    "--set", "ambient.sun.elevation_deg=40", "--set", "ambient.sun.azimuth_deg=30",
    "--set", "sensor.quantum_efficiency=nir-global-shutter",
    "--set", "sensor.filter.kind=band_pass",
]  # fmt: skip
CASES = {
    "850 nm": ["--set", "sensor.filter.cut_on_nm=830", "--set", "sensor.filter.cut_off_nm=870"],
    "940 nm": [
        "--set", "wavelength_nm=940",
        "--set", "sensor.filter.cut_on_nm=920", "--set", "sensor.filter.cut_off_nm=960",
    ],
}  # fmt: skip


def facts(summary: dict) -> dict:
    amb = summary["ambient"]
    return {
        "sunlight_through_filter_w_m2": amb["sun"]["seen_w_m2"],
        "glint_over_ambient_on_its_pixel_min": amb["glint_signal_to_ambient_min"],
        "glint_over_iris_ambient_min": min(g["over_iris_ambient"] for g in amb["glints"]),
        "weakest_glint_over_sun_brightest_pixel": amb["glint_peak_over_ambient_peak"],
        "pupil_iris_contrast_over_ambient": amb["pupil"]["signal_to_ambient"],
        "median_dn": summary["camera"]["median_dn"],
        "saturated_share": summary["camera"]["saturated_share"],
        "wall_time_s": summary["wall_time_s"],
    }


def main() -> None:
    info = C.machine()
    C.print_header("sunlight against the LEDs at 850 and 940 nm (glasses-frame)", info)
    out: dict = {"machine": info, "cases": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for name, extra in CASES.items():
            folder = Path(tmp) / name.replace(" ", "")
            cmd = ["eyelume", "render", *COMMON, *extra, "--out", str(folder)]
            print("$", shlex.join(cmd[:-2]), "--out", folder.name, flush=True)
            subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            out["cases"][name] = facts(json.loads((folder / "summary.json").read_text()))
            out["cases"][name]["command"] = shlex.join(cmd[:-2])
    out["loadavg_at_end"] = C.loadavg()
    keys = list(next(iter(out["cases"].values())))[:-1]
    print(f"{'':44s}" + "".join(f"{n:>14s}" for n in out["cases"]))
    for k in keys:
        print(f"{k:44s}" + "".join(f"{c[k]:14.4g}" for c in out["cases"].values()))
    results = Path(__file__).parent / "results" / "sunlight_850_940.jsonl"
    with results.open("a", encoding="utf-8") as f:
        f.write(json.dumps(out) + "\n")
    print(f"appended to {results}", file=sys.stderr)


if __name__ == "__main__":
    main()
