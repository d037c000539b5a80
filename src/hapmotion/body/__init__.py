"""The performer's body: per-frame body frame and the torso/vest surface model."""

from .model import BodyModel

__all__ = ["BodyModel"]
