"""Forget the frame loop's compiled cache when a module compiled into it has changed.

numba caches a compiled function beside its module (``__pycache__/kernel.render_frames-*.nbi|.nbc``) and checks
only that module's own file for changes, while the frame loop inlines the steps of :mod:`hapmotion.renderer.steps`,
the ownerless views of :mod:`.borrowed`, the body frame of :mod:`hapmotion.body.frame_compiled` and the constants
of :mod:`.packed`, :mod:`hapmotion.layout` and :mod:`hapmotion.skeleton.joints`. After an update that changed only
those, numba would load the old machine code and render what the previous version rendered. Before the loop is
compiled or loaded, :func:`forget_if_changed` compares the size and modification time of every such file with the
stamp written beside the cache and deletes the cache when they differ (numba then compiles afresh, once).
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

_PACKAGE = Path(__file__).resolve().parent.parent


def sources_stamp(files: list[Path]) -> str:
    """A digest of ``files``' paths (within the package: relative to it), sizes and modification times (ns); a missing file
    counts as such."""
    h = hashlib.sha256()
    for f in sorted(files):
        name = f.relative_to(_PACKAGE) if f.is_relative_to(_PACKAGE) else f
        try:
            st = f.stat()
            h.update(f"{name} {st.st_size} {st.st_mtime_ns}\n".encode())
        except OSError:
            h.update(f"{name} missing\n".encode())
    return h.hexdigest()


def forget_if_changed(module_file: str | Path, sources: list[Path]) -> bool:
    """Delete the numba cache of the module at ``module_file`` (its ``__pycache__/NAME.*.nbi`` and ``.nbc``) when
    ``sources`` changed since the stamp ``__pycache__/NAME.sources`` was written, and write the new stamp. True when
    the cache was forgotten. A cache folder that cannot be written (a read-only install) is left as it is."""
    module_file = Path(module_file)
    cache = module_file.parent / "__pycache__"
    stamp_file = cache / f"{module_file.stem}.sources"
    stamp = sources_stamp(sources)
    try:
        if stamp_file.read_text(encoding="ascii") == stamp:
            return False
    except (OSError, UnicodeDecodeError):
        pass
    try:
        cache.mkdir(exist_ok=True)
        for old in [*cache.glob(f"{module_file.stem}.*.nbi"), *cache.glob(f"{module_file.stem}.*.nbc")]:
            old.unlink(missing_ok=True)
        tmp = stamp_file.with_suffix(f".sources.{os.getpid()}")
        tmp.write_text(stamp, encoding="ascii")
        os.replace(tmp, stamp_file)  # whole or not at all, also with two processes starting at once
    except OSError:
        return False
    return True


def frame_loop_sources() -> list[Path]:
    """Every module compiled into the frame loop of :mod:`.kernel` (its steps, views, body frame and constants),
    :mod:`.kernel` itself included."""
    renderer = _PACKAGE / "renderer"
    return [*renderer.glob("*.py"), *(renderer / "steps").glob("*.py"), _PACKAGE / "body" / "frame.py",
            _PACKAGE / "body" / "frame_compiled.py", _PACKAGE / "layout.py", _PACKAGE / "skeleton" / "joints.py"]
