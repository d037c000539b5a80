"""Seeing what the vest feels: the self-contained HTML viewer and the static matplotlib figure.

    from hapmotion.viewer import write_page, plot_track
    write_page("show.html", [track], motion, audio=load_audio_part("song.ogg"))
    plot_track(track, "figure.png")
"""

from __future__ import annotations

from .page import AudioPart, PageInfo, build_page, load_audio_part, page_data, write_page

__all__ = ["AudioPart", "PageInfo", "build_page", "load_audio_part", "page_data", "write_page", "plot_track"]


def __getattr__(name: str):
    # matplotlib is imported only when a figure is wanted.
    if name == "plot_track":
        from .plot import plot_track

        return plot_track
    raise AttributeError(f"module 'hapmotion.viewer' has no attribute {name!r}")
