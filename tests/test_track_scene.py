"""``eyelume track --scene S``: the LEDs' layout in the picture comes from the scene, as
evaluate-tracking takes it (:func:`eyelume.analysis.tracking.evaluate.led_picture_azimuths`).

On ``paper2005-integrated`` the 45° fold mirror flips the picture left to right, so the scene's
LED azimuths (0°, 90°, 180°, 270°) are not the glints' azimuths in the picture: a user passing
``--leds 0,90,180,270`` got LEDs 0 and 2 swapped against ``truth.json`` (a fresh user's
finding). The picture here is drawn by the test from the truth of that scene (the truth's
pupil outline filled dark on a grey iris, a small bright spot at each LED's truth glint), so the
check is the labelling alone: each matched glint's LED is the truth's LED at that place.
"""

from __future__ import annotations

import json
import math

import cv2
import numpy as np
from typer.testing import CliRunner

import eyelume
from eyelume.analysis.truth import eye_truth
from eyelume.cli import app
from eyelume.compile import compile_scene

runner = CliRunner()


def _picture_from_truth(truth: dict, shape: tuple[int, int]) -> np.ndarray:
    """uint16 picture: iris 900, the truth's pupil outline filled at 120, skin 2400 outside a
    disc 2.6× the pupil, and a 1.2 px Gaussian glint of peak 4000 at each truth glint."""
    rows, cols = shape
    img = np.full(shape, 2400.0)
    cx, cy = truth["pupil"]["centre_px"]
    edge = np.asarray(truth["pupil"]["edge_px"], np.float32)
    r_pupil = float(np.mean(np.hypot(edge[:, 0] - cx, edge[:, 1] - cy)))
    yy, xx = np.mgrid[0:rows, 0:cols]
    img[(xx - cx) ** 2 + (yy - cy) ** 2 <= (2.6 * r_pupil) ** 2] = 900.0
    mask = np.zeros(shape, np.uint8)
    cv2.fillPoly(mask, [np.round(edge).astype(np.int32)], 1)
    img[mask > 0] = 120.0
    for g in truth["glints"]:
        if g["visible"]:
            gx, gy = g["centre_px"]
            img += 4000.0 * np.exp(-((xx - gx) ** 2 + (yy - gy) ** 2) / (2 * 1.2**2))
    return np.clip(img, 0, 4095).astype(np.uint16)


def _track(args: list[str]) -> tuple[int, dict | None, str]:
    res = runner.invoke(app, ["track", *args], prog_name="eyelume")
    out = json.loads(res.stdout) if res.exit_code == 0 else None
    return res.exit_code, out, res.stderr


def test_track_scene_labels_glints_as_the_truth_through_a_fold(tmp_path):
    sc = eyelume.load_scene("paper2005-integrated")
    truth = eye_truth(compile_scene(sc))
    path = tmp_path / "eye.npy"
    np.save(path, _picture_from_truth(truth, (sc.sensor.rows, sc.sensor.cols)))
    seen = [g for g in truth["glints"] if g["visible"]]
    assert len(seen) == 4

    def labels(out: dict) -> dict[int, int]:
        """Each matched glint's LED → the truth LED whose glint lies within 1 px of it."""
        got = {}
        for g in out["glints"]:
            if g.get("led") is None:
                continue
            near = [t["led"] for t in seen if math.dist(t["centre_px"], g["centre_px"]) <= 1.0]
            assert len(near) == 1, (g, seen)
            got[g["led"]] = near[0]
        return got

    code, out, err = _track([str(path), "--scene", "paper2005-integrated"])
    assert code == 0, err
    assert out["ok"], out
    got = labels(out)
    assert got == {k: k for k in range(4)}, got
    # the scene's own azimuths given by hand: the fold's flip swaps LEDs 0 and 2
    code, out, err = _track([str(path), "--leds", "0,90,180,270"])
    assert code == 0, err
    assert labels(out) == {0: 2, 1: 1, 2: 0, 3: 3}


def test_track_scene_bad_input_is_one_line(tmp_path):
    path = tmp_path / "eye.npy"
    np.save(path, np.full((30, 40), 1000, np.uint16))
    for args, says in [
        (["--scene", "paper2005", "--leds", "0,90,180,270"], "--leds and --scene"),
        (["--set", "leds.count=4"], "--set needs --scene"),
        (["--scene", "paper2005"], "the scene's sensor 87 × 65"),
        (["--scene", "no-such-preset"], "no-such-preset"),
    ]:
        res = runner.invoke(app, ["track", str(path), *args], prog_name="eyelume")
        assert res.exit_code == 2, (args, res.output)
        lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
        assert len(lines) == 1 and says in lines[0], (args, res.stderr)
