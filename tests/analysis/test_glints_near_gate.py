"""The unsmoothed search for one-pixel glints near the pupil (eyetrackvr's small sensor) is
skipped when step 2 already found as many glints of several pixels as there are LEDs: it would
find nothing more there, and cost 1.3 ms of a 640 × 400 frame's ~7. Without LEDs, or with
fewer such glints, it runs."""

from __future__ import annotations

import importlib

from tests.analysis.test_detect import LEDS, draw_eye

D = importlib.import_module("eyelume.analysis.tracking.detect")  # the module, not detect()


def test_no_search_when_every_led_has_a_resolved_glint(monkeypatch):
    calls = []
    real = D.glints_near

    def counted(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(D, "glints_near", counted)
    img = draw_eye()
    d = D.detect(img, led_azimuths_deg=LEDS)
    assert d.ok and sum(g.led is not None for g in d.glints) == 4
    # (the small-pupil pass's own search, _sharp_glints, runs only when no whole pupil is found)
    assert calls == []
    d5 = D.detect(img, led_azimuths_deg=(*LEDS, 45.0))  # a fifth LED: one glint short
    assert calls, "the search runs when an LED may have lost its glint"
    assert sum(g.led is not None for g in d5.glints) == 4
    calls.clear()
    D.detect(img)
    assert calls, "without LEDs the search runs"
