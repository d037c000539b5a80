"""The frame loop's numba cache is forgotten when a module compiled into it changes (numba checks only the loop's own
file), and kept otherwise."""

from __future__ import annotations

import os

from hapmotion.renderer.compiled_cache import forget_if_changed, frame_loop_sources


def _module(tmp_path):
    module = tmp_path / "kernel.py"
    module.write_text("# loop\n")
    step = tmp_path / "step.py"
    step.write_text("X = 1\n")
    cache = tmp_path / "__pycache__"
    cache.mkdir()
    return module, step, cache


def _cached(cache):
    for name in ("kernel.render_frames-94.py311.nbi", "kernel.render_frames-94.py311.1.nbc"):
        (cache / name).write_bytes(b"machine code")
    (cache / "other.f-1.py311.nbi").write_bytes(b"another module's")


def test_a_changed_step_forgets_the_loops_cache_and_only_it(tmp_path):
    module, step, cache = _module(tmp_path)
    assert forget_if_changed(module, [module, step])  # no stamp yet: whatever is there may be stale
    _cached(cache)
    assert not forget_if_changed(module, [module, step])  # nothing changed: the cache stays
    assert len(list(cache.glob("kernel.*.nb*"))) == 2

    step.write_text("X = 2  # a changed constant\n")
    os.utime(step, ns=(1, 1))  # a different modification time as well as size
    assert forget_if_changed(module, [module, step])
    assert not list(cache.glob("kernel.*.nb*"))
    assert (cache / "other.f-1.py311.nbi").exists()
    assert not forget_if_changed(module, [module, step])


def test_a_removed_source_counts_as_a_change(tmp_path):
    module, step, cache = _module(tmp_path)
    forget_if_changed(module, [module, step])
    _cached(cache)
    step.unlink()
    assert forget_if_changed(module, [module, step])
    assert not list(cache.glob("kernel.*.nb*"))


def test_the_loops_sources_are_the_modules_it_compiles_in():
    names = {f"{p.parent.name}/{p.name}" for p in frame_loop_sources()}
    assert {"renderer/kernel.py", "renderer/borrowed.py", "renderer/packed.py", "steps/choice.py",
            "steps/triangle.py", "body/frame_compiled.py", "hapmotion/layout.py"} <= names
    assert all(p.exists() for p in frame_loop_sources())
