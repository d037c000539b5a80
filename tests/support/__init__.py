"""Helpers shared by the tests and benchmarks: data paths, synthetic motions and songs, fakes of the network peers.

The tests import this package as ``support`` (pytest puts ``tests/`` on the path); the benchmarks, run from the
repository root as ``python -m benchmarks.NAME``, import it as ``tests.support``. Modules here import each other
relatively, so both work."""
