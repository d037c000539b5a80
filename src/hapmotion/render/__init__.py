"""The motion renderer: the paper's MST pipeline (and its baseline) from joints to actuator intensities."""

from .params import PRESETS, Params, get_preset
from .renderer import Renderer, render

__all__ = ["PRESETS", "Params", "Renderer", "get_preset", "render"]
