"""The motion renderer: the paper's MST pipeline (and its baseline) from joints to actuator intensities.

- ``params``: every parameter, its range and the presets;
- ``renderer``: ``Renderer`` (one frame at a time, sans-I/O) and ``render`` (a whole recording);
- ``kernel``: the compiled frame loop both of them run; ``steps``: one compiled module per step of the paper;
- ``packed``: where each value sits in the flat arrays the frame loop works on.
"""

from .params import PRESETS, Params, get_preset
from .renderer import Renderer, render

__all__ = ["PRESETS", "Params", "Renderer", "get_preset", "render"]
