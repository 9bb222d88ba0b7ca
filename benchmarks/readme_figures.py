"""The README's main figures, made from the built-in presets with the `eyelume` command as a user
runs it, and written small under ``docs/figures/`` (each at most ``--width`` pixels wide).

    python benchmarks/readme_figures.py [--width 900] [--samples 8] [--tracking-samples 4]
                                        [--only GROUP ...]

Writes ``eye_image_plot.png`` and ``layout.png`` (``eyelume render --scene paper2005``),
``layout_vr-offaxis_xz.png`` (``eyelume render --scene vr-offaxis``, its x–z view),
``landscape.png`` (``eyelume sweep-leds``) and ``error_maps.png``
(``eyelume evaluate-tracking --samples N``), and the presets' pictures the README shows under
``docs/presets/`` (``vr-offaxis_eye_image.png``, ``vr-offaxis_layout_xz.png``,
``eyetrackvr_eye_image.png``, ``glasses-frame_eye_image.png``: each ``eye_image_plot.png`` of
``eyelume render --scene NAME``), and prints each command and its wall time. The figures are
eyelume's own files, only downscaled (Pillow, Lanczos); nothing is drawn here.

``--only`` makes just some of them (all take ~25 min): ``paper2005`` (eye image and layout),
``vr-offaxis``, ``presets`` (eyetrackvr, glasses-frame), ``landscape``, ``error_maps``.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

from PIL import Image

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "figures"
PRESETS = ROOT / "docs" / "presets"
#: The figure groups ``--only`` chooses from (module doc).
GROUPS = ("paper2005", "vr-offaxis", "presets", "landscape", "error_maps")


def run(args: list[str]) -> None:
    t0 = time.perf_counter()
    print("$ eyelume " + " ".join(args), flush=True)
    subprocess.run([shutil.which("eyelume") or "eyelume", *args], check=True)
    print(f"  {time.perf_counter() - t0:.0f} s", flush=True)


def small(src: Path, name: str, width: int, out: Path = OUT) -> None:
    with Image.open(src) as im:
        im = im.convert("RGB")
        if im.width > width:
            im = im.resize((width, round(im.height * width / im.width)), Image.LANCZOS)
        out.mkdir(parents=True, exist_ok=True)
        im.save(out / name, optimize=True)
    print(f"  wrote {(out / name).relative_to(ROOT)} ({(out / name).stat().st_size // 1024} kB)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--width", type=int, default=900)
    ap.add_argument("--samples", type=int, default=8, help="render samples per pixel")
    ap.add_argument("--tracking-samples", type=int, default=4)
    ap.add_argument("--only", nargs="+", choices=GROUPS, default=list(GROUPS),
                    help="make only these figure groups (default: all)")  # fmt: skip
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        t = Path(tmp)
        if "paper2005" in a.only:
            run(["render", "--scene", "paper2005", "--samples", str(a.samples),
                 "--out", str(t / "r")])  # fmt: skip
            small(t / "r" / "eye_image_plot.png", "eye_image_plot.png", a.width)
            small(t / "r" / "layout.png", "layout.png", a.width)
        if "vr-offaxis" in a.only:
            run(["render", "--scene", "vr-offaxis", "--samples", str(a.samples),
                 "--out", str(t / "v")])  # fmt: skip
            small(t / "v" / "layout_xz.png", "layout_vr-offaxis_xz.png", a.width)
            small(t / "v" / "eye_image_plot.png", "vr-offaxis_eye_image.png", a.width, PRESETS)
            small(t / "v" / "layout_xz.png", "vr-offaxis_layout_xz.png", a.width, PRESETS)
        if "presets" in a.only:
            for scene, spp in (("eyetrackvr", 4), ("glasses-frame", 2)):  # as the README says
                run(["render", "--scene", scene, "--samples", str(spp), "--out", str(t / scene)])
                small(t / scene / "eye_image_plot.png", f"{scene}_eye_image.png", a.width,
                      PRESETS)  # fmt: skip
        if "landscape" in a.only:
            run(["sweep-leds", "--out", str(t / "s")])
            small(t / "s" / "landscape.png", "landscape.png", a.width)
        if "error_maps" in a.only:
            run(["evaluate-tracking", "--samples", str(a.tracking_samples),
                 "--out", str(t / "e")])  # fmt: skip
            small(t / "e" / "error_maps.png", "error_maps.png", a.width)
        shutil.rmtree(t, ignore_errors=True)


if __name__ == "__main__":
    main()
