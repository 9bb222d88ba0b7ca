"""Eye tracking from the camera picture: pupil and glint segmentation, gaze estimation.

:func:`detect` is the paper's Figure 2 pipeline on any grey picture (:mod:`.detect`).
"""

from eyelume.analysis.tracking.detect import (
    Detection,
    DetectParams,
    Glint,
    Pupil,
    detect,
    detection_to_dict,
    enlargement_factor,
)

__all__ = [
    "DetectParams",
    "Detection",
    "Glint",
    "Pupil",
    "detect",
    "detection_to_dict",
    "enlargement_factor",
]
