"""Pupil detection on real near-infrared eye pictures with human-drawn pupil masks (issue 13).

Run from the repository root::

    python benchmarks/detect_real.py                  # ../shared/realdata beside the clone
    python benchmarks/detect_real.py --data DIR       # another copy of the data set
    python benchmarks/detect_real.py --record         # and append the table to results/

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
- **axes**: the median and 90th percentile of the full axes' error (px; major and minor
  pooled, each against the mask ellipse's ``ell_major_px`` / ``ell_minor_px``) of the answers
  within 5 px — the pupil's size a pupillometry user reads (the masks are drawn ellipses, good
  to about a pixel);
- **ms**: median time per picture;
- the refusal causes (the failure messages with their numbers blanked, counted).

Where ``pupil-detectors`` (Pupil Labs' 2D detector) is installed, the same table for it (found
= confidence ≥ 0.6, Pupil Capture's default threshold for using a pupil datum), side by side.
Install it with ``pip install --no-deps pupil-detectors==2.0.2``: its wheel bundles its own
OpenCV libraries and imports ``cv2`` from whichever build is installed, but its metadata
requires ``opencv-python``, which pip would install beside eyelume's
``opencv-python-headless`` — two distributions writing one ``cv2`` folder, where uninstalling
or upgrading either breaks the other. So it is in no extra. Without it, the Pupil Labs rows of
the last run that had it are printed from ``benchmarks/results/detect_real.jsonl``, marked as
recorded, with that run's date, commit and ``pupil-detectors`` version.

The ``itmo`` crops are centred on the pupil, so the row "centre guess" (the picture's centre as
the answer) is the baseline a detector must beat.

The pictures are for internal evaluation only (their README): this script reads them where they
are; it stores only the table's aggregate rows (``benchmarks/results/detect_real.jsonl``), no
picture, crop or per-picture figure.
"""

from __future__ import annotations

import argparse
import csv
import json
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
RECORD = REPO / "benchmarks" / "results" / "detect_real.jsonl"
PL_MIN_CONFIDENCE = 0.6
PL_RECORDED = "pupil-labs (recorded)"


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
    """Per source: lists of (error or None, ms, cause, axes' errors or None) per picture for
    each detector (the axes' errors: |major − ell_major_px|, |minor − ell_minor_px|, px)."""
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
        axes = (float(r["ell_major_px"]), float(r["ell_minor_px"]))
        src = out.setdefault(r["source"], {"eyelume": [], "pupil-labs": [], "centre guess": []})
        t0 = time.perf_counter()
        d = detect(img)
        ms = 1e3 * (time.perf_counter() - t0)
        if d.ok and d.pupil is not None:
            err = float(np.hypot(*(np.array(d.pupil.centre_px) - truth)))
            src["eyelume"].append((err, ms, None, _axes_error(d.pupil.axes_px, axes)))
        else:
            errs = [f for f in d.failures if not f.startswith("warning")]
            src["eyelume"].append((None, ms, _cause(errs[0]) if errs else "no answer", None))
        h, w = img.shape[:2]
        guess = float(np.hypot(*(np.array([w / 2, h / 2]) - truth)))
        src["centre guess"].append((guess, 0, None, None))
        if pl is not None:
            u8 = img if img.dtype == np.uint8 else cv2.normalize(img, None, 0, 255, 32, cv2.CV_8U)
            t0 = time.perf_counter()
            res = pl.detect(np.ascontiguousarray(u8))
            ms = 1e3 * (time.perf_counter() - t0)
            if res["confidence"] >= PL_MIN_CONFIDENCE:
                err = float(np.hypot(*(np.array(res["ellipse"]["center"]) - truth)))
                src["pupil-labs"].append((err, ms, None, _axes_error(res["ellipse"]["axes"], axes)))
            else:
                src["pupil-labs"].append((None, ms, f"confidence < {PL_MIN_CONFIDENCE}", None))
    return out


def _axes_error(found, truth) -> tuple[float, float]:
    """|major − major'|, |minor − minor'| (px) of a found ellipse's full axes (any order)
    against the annotation's."""
    big, small = max(found), min(found)
    return abs(big - truth[0]), abs(small - truth[1])


def summary_rows(results: dict[str, dict[str, list]]) -> list[dict]:
    """One aggregate row per source and detector (no per-picture figure): n, found %, ≤ 5 px %,
    median and p95 error (px) of those found, wrong (> 5 px off), median ms, refusal causes."""
    rows = []
    for src, dets in results.items():
        for name, rec in dets.items():
            if not rec:
                continue
            n = len(rec)
            errs = [r_[0] for r_ in rec if r_[0] is not None]
            ax = [a for r_ in rec if r_[0] is not None and r_[0] <= 5.0 and r_[3] for a in r_[3]]
            rows.append(
                {
                    "source": src,
                    "detector": name,
                    "n": n,
                    "found_pct": 100 * len(errs) / n,
                    "within5_pct": 100 * sum(e <= 5.0 for e in errs) / n,
                    "median_px": statistics.median(errs) if errs else None,
                    "p95_px": float(np.percentile(errs, 95)) if errs else None,
                    "wrong": sum(e > 5.0 for e in errs),
                    "axes_median_px": statistics.median(ax) if ax else None,
                    "axes_p90_px": float(np.percentile(ax, 90)) if ax else None,
                    "ms": statistics.median(r_[1] for r_ in rec),
                    "refusals": dict(
                        Counter(r_[2] for r_ in rec if r_[2] is not None).most_common()
                    ),
                }
            )
    return rows


def recorded_pupil_labs(path: Path = RECORD) -> tuple[list[dict], str] | None:
    """The Pupil Labs rows of the last recorded run that had ``pupil-detectors``, renamed
    :data:`PL_RECORDED`, and a line saying where they come from; None when there is none."""
    if not path.is_file():
        return None
    last = None
    for line in path.read_text().splitlines():
        rec = json.loads(line) if line.strip() else {}
        if rec.get("pupil_detectors"):
            last = rec
    if last is None:
        return None
    rows = [{**r, "detector": PL_RECORDED} for r in last["rows"] if r["detector"] == "pupil-labs"]
    git = last.get("git", {})
    where = (
        f"{PL_RECORDED}: from {path.relative_to(REPO)}, run {last.get('time_utc')} at commit "
        f"{git.get('commit', '?')} with pupil-detectors {last['pupil_detectors']} "
        f"({last.get('data')})"
    )
    return rows, where


def _fmt(v, spec: str) -> str:
    return format(v, spec) if v is not None else format(float("nan"), spec)


def table(rows: list[dict]) -> str:
    head = f"{'source':8} {'detector':21} {'n':>4} {'found':>6} {'≤5 px':>6} {'median':>7} "
    head += f"{'p95':>7} {'wrong':>6} {'axes':>11} {'ms':>6}"
    lines = [head, "-" * len(head)]
    causes = []
    for r in sorted(rows, key=lambda r: r["source"]):
        lines.append(
            f"{r['source']:8} {r['detector']:21} {r['n']:4d} {r['found_pct']:5.1f}% "
            f"{r['within5_pct']:5.1f}% {_fmt(r['median_px'], '7.2f')} {_fmt(r['p95_px'], '7.2f')} "
            f"{r['wrong']:6d} {_fmt(r.get('axes_median_px'), '5.2f')}/"
            f"{_fmt(r.get('axes_p90_px'), '5.2f')} {r['ms']:6.1f}"
        )
        if r["detector"] == "eyelume":
            causes.append(f"{r['source']}: eyelume refusals ({sum(r['refusals'].values())}):")
            causes += [f"  {k:4d} × {v}" for v, k in r["refusals"].items()]
    return "\n".join(lines + [""] + causes)


def _git_commit() -> str:
    try:
        return subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"], cwd=REPO, capture_output=True, text=True
        ).stdout.strip()
    except OSError:
        return "?"


def record(rows: list[dict], data: Path, pl_version: str | None) -> Path:
    """Append this run's aggregate rows (no per-picture figure) to :data:`RECORD`."""
    RECORD.parent.mkdir(parents=True, exist_ok=True)
    rec = {
        "time_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "command": "python benchmarks/detect_real.py",
        "git": {"commit": _git_commit()},
        "opencv": cv2.__version__,
        "pupil_detectors": pl_version,
        "pupil_labs_min_confidence": PL_MIN_CONFIDENCE,
        "data": f"realdata/labels.csv, {sum(r['n'] for r in rows if r['detector'] == 'eyelume')}"
        " pictures",
        "rows": rows,
    }
    with RECORD.open("a") as fh:
        fh.write(json.dumps(rec) + "\n")
    return RECORD


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=None, help="the realdata folder")
    ap.add_argument(
        "--record",
        action="store_true",
        help="append the aggregate rows to benchmarks/results/detect_real.jsonl",
    )
    args = ap.parse_args(argv)
    data = find_data(args.data)
    if data is None:
        where = args.data or REPO.parent / "shared" / "realdata"
        print(f"detect_real: skipped — no realdata/labels.csv at {where} (internal data set)")
        return 0
    cv2.setNumThreads(1)
    pl_version = None
    notes = []
    if _pupil_labs() is None:
        notes.append(
            "detect_real: pupil-detectors (Pupil Labs 2D) is not installed (pip install "
            "--no-deps pupil-detectors==2.0.2; module doc for why --no-deps)"
        )
    else:
        from importlib.metadata import version

        pl_version = version("pupil-detectors")
    print(f"detect_real: {data}")
    rows = summary_rows(run(data))
    shown = list(rows)
    if pl_version is None:
        old = recorded_pupil_labs()
        if old is None:
            notes.append("detect_real: and no recorded Pupil Labs run: its rows are left out")
        else:
            shown += old[0]
            notes.append(old[1])
    print(table(shown))
    for n in notes:
        print(n)
    if args.record:
        print(f"detect_real: appended to {record(rows, data, pl_version).relative_to(REPO)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
