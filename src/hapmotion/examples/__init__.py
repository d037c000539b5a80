"""Bundled example recordings and music (see ATTRIBUTION.md beside this file)."""
