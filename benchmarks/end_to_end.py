"""Wall time of two commands, end to end in a fresh process each (issues 4 and 5): reproduce
(the paper's δ study) and evaluate-tracking.

    python benchmarks/end_to_end.py          # reproduce + evaluate-tracking, ~1.5 min
    python benchmarks/end_to_end.py --only reproduce

- ``reproduce``: ``eyelume reproduce paper2005 --out TMP`` with its defaults (9 δ, 32 camera
  samples per pixel per eye image, 30 renders of direct optimisation). Target ≤ 60 s.
- ``tracking``: ``eyelume evaluate-tracking --out TMP`` (7 × 5 test gazes + 9 calibration
  gazes, 16 samples per pixel at the preset's 87 × 65), with the per-frame render and detection
  times it reports.

Each runs after a warm-up process has filled the Numba cache, so compilation is not timed.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from _common import command_line, loadavg, machine, print_header  # noqa: E402

RESULTS = Path(__file__).parent / "results" / "end_to_end.jsonl"


def run(args: list[str]) -> float:
    t0 = time.perf_counter()
    cmd = [sys.executable, "-c", "from eyelume.cli import app; app()", *args]
    subprocess.run(cmd, check=True, capture_output=True)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", default="reproduce,tracking")
    a = ap.parse_args()
    info = {"machine": machine(), "command": command_line(), "load_start": loadavg()}
    print_header("reproduce and evaluate-tracking, end to end", info["machine"])
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        # warm the Numba cache (render, reproduce's kernels, tracking) in throwaway runs
        run(["render", "--out", f"{tmp}/w"])
        if "reproduce" in a.only:
            warm = ["--deltas", "0.3", "--direct", "2", "--out", f"{tmp}/w2"]
            run(["reproduce", "paper2005", *warm])
            wall = run(["reproduce", "paper2005", "--out", f"{tmp}/r"])
            delta_study = json.loads(Path(f"{tmp}/r/delta_study.json").read_text())
            out["reproduce"] = {"wall_s": wall, "best_delta": delta_study["best_delta"]}
            status = "PASS" if wall <= 60 else "FAIL"
            print(f"[{status}] eyelume reproduce paper2005: {wall:.1f} s (target ≤ 60 s)")
        if "tracking" in a.only:
            wall = run(["evaluate-tracking", "--out", f"{tmp}/t"])
            s = json.loads(Path(f"{tmp}/t/summary.json").read_text())
            out["tracking"] = {
                "wall_s": wall,
                "render_s_per_frame": s["render_s_per_frame"],
                "detect_ms_per_frame": s["detect_ms_per_frame"],
                "detection_rate": s["detection_rate"],
                "gaze_pccr": s["gaze_pccr"],
                "gaze_geometric": s["gaze_geometric"],
                "pupil_error_px": s["pupil_error_px"],
            }
            print(
                f"[info] eyelume evaluate-tracking: {wall:.1f} s for 44 frames; render "
                f"{s['render_s_per_frame']:.2f} s/frame, detection "
                f"{s['detect_ms_per_frame']:.2f} ms/frame (87 × 65); detection rate "
                f"{s['detection_rate']:.0%}"
            )
    info["load_end"] = loadavg()
    RESULTS.parent.mkdir(exist_ok=True)
    with open(RESULTS, "a", encoding="utf-8") as f:
        f.write(json.dumps({**info, **out}) + "\n")


if __name__ == "__main__":
    main()
