"""A parsed SOURCE or SINK string: :class:`Endpoint` (what :mod:`hapmotion.live.urls` returns, and what the kinds'
factories and the sources take)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

from ..errors import UsageError


@dataclass
class Endpoint:
    """A parsed SOURCE or SINK: ``kind``, network address or file path, path/prefix and query options."""

    kind: str
    host: str = ""
    port: int = 0
    path: str = ""
    options: dict[str, list[str]] = field(default_factory=dict)
    text: str = ""

    def option(self, name: str, default: Optional[str] = None) -> Optional[str]:
        values = self.options.get(name)
        return values[-1] if values else default

    def flag(self, name: str, default: bool = True) -> bool:
        v = self.option(name)
        if v is None:
            return default
        if v.lower() in ("1", "true", "yes", "on"):
            return True
        if v.lower() in ("0", "false", "no", "off"):
            return False
        raise UsageError(f"{self.text}: option {name}={v}: expected 0 or 1")

    def int_option(self, name: str) -> Optional[int]:
        v = self.option(name)
        if v is None:
            return None
        try:
            n = int(v)
        except ValueError:
            raise UsageError(f"{self.text}: option {name}={v}: expected a whole number") from None
        if n <= 0:
            raise UsageError(f"{self.text}: option {name}={v}: expected a positive number")
        return n
