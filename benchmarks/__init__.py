"""Benchmarks: each prints its figures beside their targets.

Run one from the repository root as a module, ``python -m benchmarks.NAME [OPTIONS]`` (``make bench`` runs the
main ones), with hapmotion importable (``make install``, or ``PYTHONPATH=src``). They share the tests' helpers
(data paths, synthetic motions and songs, fake Players) as the package ``tests.support``.
"""
