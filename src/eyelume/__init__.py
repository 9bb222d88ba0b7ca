"""eyelume: near-infrared illumination design for eye trackers in head-mounted displays.

>>> import eyelume
>>> scene = eyelume.load_scene("paper2005")
>>> scene.leds.count
4
"""

from eyelume.errors import EyelumeError, SceneError
from eyelume.render import RenderResult, render
from eyelume.scene.io import apply_overrides, load_scene, save_scene

__all__ = [
    "EyelumeError",
    "RenderResult",
    "SceneError",
    "apply_overrides",
    "load_scene",
    "render",
    "save_scene",
]
__version__ = "0.1.0"
