"""Pupil detection on real near-infrared eye pictures with human-drawn pupil masks (issue 13).

Run from the repository root::

    python benchmarks/detect_real.py                  # ../shared/realdata beside the clone
    python benchmarks/detect_real.py --data DIR       # another copy of the data set

Reads ``realdata/labels.csv`` (``../shared/realdata`` beside the clone; from a git worktree,
beside the main checkout too) and runs :func:`eyelume.analysis.tracking.detect` on every
picture, on one core (``cv2.setNumThreads(1)``). Per source (``itmo``: 252 close-ups of 21
people; ``openeds``: 3 frames of a VR headset's eye camera) it prints:

- **found**: share of pictures where ``detect`` answers ``ok`` with a pupil;
- **≤ 5 px**: share of *all* pictures answered within 5 px of the annotation's centre (the
  centre of the ellipse ``cv2.fitEllipse`` fits to the mask's outline, OpenCV's pixel
  convention, as eyelume's);
- **median / p95**: the centre error (px) of those found;
- **wrong**: answers more than 5 px off (the iris, a border, a lash taken as the pupil);
- **ms**: median time per picture;
- the refusal causes (the failure messages with their numbers blanked, counted).

Where ``pupil-detectors`` (Pupil Labs' 2D detector; ``pip install -e .[bench]``) is installed,
the same table for it (found = confidence ≥ 0.6, Pupil Capture's default threshold for using a
pupil datum), side by side. The ``itmo`` crops are centred on the pupil, so the row "centre
guess" (the picture's centre as the answer) is the baseline a detector must beat.

The pictures are for internal evaluation only (their README): this script reads them where they
are and writes nothing; no picture, crop or per-picture figure is stored in the repository.
"""

from __future__ import annotations

import argparse
import csv
import re
import statistics
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import cv2
import numpy as np

from eyelume.analysis.tracking import detect

REPO = Path(__file__).resolve().parent.parent
PL_MIN_CONFIDENCE = 0.6


def find_data(explicit: Path | None) -> Path | None:
    """The realdata folder: ``explicit``, else ``../shared/realdata`` beside this clone, else
    beside the main checkout when this is a git worktree."""
    if explicit is not None:
        return explicit if (explicit / "labels.csv").is_file() else None
    candidates = [REPO.parent / "shared" / "realdata"]
    try:
        common = subprocess.run(
            ["git", "rev-parse", "--path-format=absolute", "--git-common-dir"],
            cwd=REPO,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
        candidates.append(Path(common).parent.parent / "shared" / "realdata")
    except (OSError, subprocess.CalledProcessError):
        pass
    for c in candidates:
        if (c / "labels.csv").is_file():
            return c
    return None


def _cause(msg: str) -> str:
    """A failure message with its numbers blanked, so like causes count together."""
    head = msg.split(":")[0] if msg.startswith("glint") else msg
    return re.sub(r"-?\d+(\.\d+)?", "N", head)[:90]


def _pupil_labs():
    try:
        from pupil_detectors import Detector2D
    except ImportError:
        return None
    return Detector2D()


def run(data: Path) -> dict[str, dict[str, list]]:
    """Per source: lists of (error or None, ms, cause) per picture for each detector."""
    rows = list(csv.DictReader((data / "labels.csv").open()))
    pl = _pupil_labs()
    out: dict[str, dict[str, list]] = {}
    for r in rows:
        img = cv2.imread(str(data / r["file"]), cv2.IMREAD_UNCHANGED)
        if img is None:
            raise SystemExit(f"detect_real: cannot read {data / r['file']}")
        if img.ndim == 3:
            img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
        truth = np.array([float(r["pupil_x"]), float(r["pupil_y"])])
        src = out.setdefault(r["source"], {"eyelume": [], "pupil-labs": [], "centre guess": []})
        t0 = time.perf_counter()
        d = detect(img)
        ms = 1e3 * (time.perf_counter() - t0)
        if d.ok and d.pupil is not None:
            err = float(np.hypot(*(np.array(d.pupil.centre_px) - truth)))
            src["eyelume"].append((err, ms, None))
        else:
            errs = [f for f in d.failures if not f.startswith("warning")]
            src["eyelume"].append((None, ms, _cause(errs[0]) if errs else "no answer"))
        h, w = img.shape[:2]
        src["centre guess"].append((float(np.hypot(*(np.array([w / 2, h / 2]) - truth))), 0, None))
        if pl is not None:
            u8 = img if img.dtype == np.uint8 else cv2.normalize(img, None, 0, 255, 32, cv2.CV_8U)
            t0 = time.perf_counter()
            res = pl.detect(np.ascontiguousarray(u8))
            ms = 1e3 * (time.perf_counter() - t0)
            if res["confidence"] >= PL_MIN_CONFIDENCE:
                err = float(np.hypot(*(np.array(res["ellipse"]["center"]) - truth)))
                src["pupil-labs"].append((err, ms, None))
            else:
                src["pupil-labs"].append((None, ms, f"confidence < {PL_MIN_CONFIDENCE}"))
    return out


def table(results: dict[str, dict[str, list]]) -> str:
    head = f"{'source':8} {'detector':13} {'n':>4} {'found':>6} {'≤5 px':>6} {'median':>7} "
    head += f"{'p95':>7} {'wrong':>6} {'ms':>6}"
    lines = [head, "-" * len(head)]
    causes = []
    for src, dets in results.items():
        for name, rec in dets.items():
            if not rec:
                continue
            n = len(rec)
            errs = [e for e, _, _ in rec if e is not None]
            within = sum(e <= 5.0 for e in errs)
            wrong = sum(e > 5.0 for e in errs)
            med = statistics.median(errs) if errs else float("nan")
            p95 = float(np.percentile(errs, 95)) if errs else float("nan")
            ms = statistics.median(t for _, t, _ in rec)
            found = f"{100 * len(errs) / n:5.1f}%"
            lines.append(
                f"{src:8} {name:13} {n:4d} {found:>6} {100 * within / n:5.1f}% {med:7.2f} "
                f"{p95:7.2f} {wrong:6d} {ms:6.1f}"
            )
            if name == "eyelume":
                c = Counter(cause for _, _, cause in rec if cause is not None)
                causes.append(f"{src}: eyelume refusals ({sum(c.values())}):")
                causes += [f"  {k:4d} × {v}" for v, k in c.most_common()]
    return "\n".join(lines + [""] + causes)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=None, help="the realdata folder")
    args = ap.parse_args(argv)
    data = find_data(args.data)
    if data is None:
        where = args.data or REPO.parent / "shared" / "realdata"
        print(f"detect_real: skipped — no realdata/labels.csv at {where} (internal data set)")
        return 0
    cv2.setNumThreads(1)
    if _pupil_labs() is None:
        print(
            "detect_real: pupil-detectors (Pupil Labs 2D) is not installed "
            "(pip install -e .[bench]): its table is left out"
        )
    print(f"detect_real: {data}")
    print(table(run(data)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
