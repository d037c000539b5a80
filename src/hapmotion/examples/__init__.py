"""Bundled example recordings, music and patterns (see ATTRIBUTION.md beside this file; the patterns are built by
:mod:`hapmotion.examples.patterns`)."""
