"""A pupil joined to a shadowed iris beside it before its ladder chain is stable (issue 13;
README's Open list since session 27: "a sun shadow's edge on a dark iris fitted, 65 px off").

Where the pupil joins a dark region beside it (a little lighter) a level or two up the
ladder, its chain's stable blob is the two together, refused as not compact, and the pupil
alone — the chain's
blob before that jump in area — was never tried: MSER's q of it is the jump's, over 1. When a
chosen blob is not compact, the blob before its chain's largest jump (≥ 2 ×) is now tried
(:func:`eyelume.analysis.tracking.pupil._before_jump`).

``tests/reference/population_sun_shadow_850nm.npz``: the digital picture (``counts``, 400 × 400
uint16 DN) of ``python benchmarks/design_850_940.py --people 5 --workers 1 --set
sensor.exposure_ms=1 --set run.indirect=cache --keep DIR`` at commit 4d274f9: person 4 of
population seed 1 on ``vr-offaxis`` at 850 nm, test frame (0°, −5°), the sun on; pupil 16 DN,
the iris 50–60 DN but 23–29 DN where the lid's and the sun's shadows fall, the sunlit sclera
600–700 DN (3 levels between pupil and shadow in the 8-bit working picture); with the truth's
pupil outline (``pupil_edge_px``) and the LEDs' azimuths and predicted glint layout that
``evaluate-tracking`` passes. Before: ``ok`` with a patch on the shadow's edge (37 × 21 px)
as the pupil, 65 px off.

Tolerances: the issue's 1 px for the centre and the axes (the ellipse fitted to the truth's
outline; its rms 0.02 px).
"""

from __future__ import annotations

import math
from pathlib import Path

from eyelume.analysis.tracking.pupil import Candidate, _before_jump
from tests.analysis.test_detect_pupil_shot_noise import (
    assert_pupil_is_the_truths,
    detect_kept_frame,
)

FIXTURE = Path(__file__).parents[1] / "reference" / "population_sun_shadow_850nm.npz"


def _chain(*areas: int) -> list[Candidate]:
    return [Candidate(float(i), a, (0, 0, 1, 1), (0, 0), index=i) for i, a in enumerate(areas)]


def test_the_blob_before_the_largest_jump_up_to_the_pick():
    ch = _chain(80, 95, 297, 310, 337, 367)  # the fixture's finer ladder, pupil then joined
    assert _before_jump(ch, 3) is ch[1]
    assert _before_jump(ch, 1) is None  # nothing before the pick grows 2 ×
    ch = _chain(10, 25, 45, 200, 210)  # two jumps: the larger (4.4 ×) counts
    assert _before_jump(ch, 4) is ch[2]
    assert _before_jump(_chain(50, 60, 70, 80), 3) is None
    # a speck that started the chain (under ⅕ of the picked blob's area) is no hidden pupil: a
    # render where it was answered ok, 47 px off (2 reduced px, then 386)
    assert _before_jump(_chain(2, 386, 400), 2) is None
    ch = _chain(30, 40, 150, 160)  # 40 ≥ 0.2 × 160: counts
    assert _before_jump(ch, 3) is ch[1]


def test_pupil_joined_to_a_sun_shadowed_iris_is_found_not_the_shadows_edge():
    assert_pupil_is_the_truths(*detect_kept_frame(FIXTURE))


#: Session 31's first rendering of the same design run (commit 930bd44, the same command): person
#: 4 at 850 nm, test frame (10°, −5°), with the truth's pupil outline worked out at 4d274f9.
SPECK = Path(__file__).parents[1] / "reference" / "population_speck_chain_850nm.npz"


def test_a_speck_that_started_the_chain_is_not_answered_as_the_pupil():
    """The chain the ladder picked began as a 2 px speck (reduced 5 ×) beside a glint in the
    iris and jumped to 386 px, the pupil with the dark iris about it, not compact. Before the
    share rule, the speck's blob was fitted and answered ``ok``, 47 px off the pupil. Now it
    is not tried: the answer must be right (within the issue's 1 px) or a refusal."""
    d, truth = detect_kept_frame(SPECK)
    if d.ok:
        assert math.dist(d.pupil.centre_px, truth["center_px"]) < 1.0, (d.pupil, d.failures)
