"""Colour scales for intensities 0..100, shared by the HTML page and the static plot.

* Page (dark theme): an "off" grey for 0, then matplotlib's perceptually uniform ``inferno`` from dark red-purple
  to bright yellow, so a motor glows brighter the harder it runs.
* Plot (printed on white paper): 0 is white (nothing to print where nothing runs), then ``magma_r`` from light
  yellow to near black, monotonic in lightness so it survives greyscale printing.
"""

from __future__ import annotations

import numpy as np

SCALE_TOPS = (5, 10, 20, 25, 50, 100)
"""Colour-scale tops offered by the page and the plot; "fit" takes the smallest one at or above the peak, so a weak
track (the paper preset rarely passes 25) stays readable. The scale in use is always printed beside the colours."""

OFF_COLOR = "#1b1d22"
"""Page colour of a motor at intensity 0 (the cell background)."""

PAGE_CMAP = "inferno"
PAGE_CMAP_RANGE = (0.25, 1.0)  # inferno below 0.25 is too close to "off" on a dark page: 1 must be visible
PLOT_CMAP = "magma_r"
PLOT_CMAP_RANGE = (0.0, 0.92)  # the last 8 % of magma_r is black, too close to the grid lines


def page_colors() -> list[str]:
    """101 ``#rrggbb`` colours for the page: index = whole intensity 0..100."""
    import matplotlib

    cmap = matplotlib.colormaps[PAGE_CMAP]
    lo, hi = PAGE_CMAP_RANGE
    rgba = cmap(np.linspace(lo, hi, 100))
    return [OFF_COLOR] + ["#%02x%02x%02x" % tuple(int(round(255 * c)) for c in row[:3]) for row in rgba]


def bright_from(colors: list[str], threshold: float = 0.55) -> int:
    """First intensity whose page colour is light enough (relative luminance >= threshold) for dark label text."""
    for i, c in enumerate(colors):
        r, g, b = (int(c[k:k + 2], 16) / 255.0 for k in (1, 3, 5))
        if 0.2126 * r + 0.7152 * g + 0.0722 * b >= threshold:
            return i
    return len(colors)


def plot_cmap():
    """Matplotlib colormap for the printed heat map; values below 0.5 (i.e. 0) are drawn white."""
    import matplotlib
    from matplotlib.colors import ListedColormap

    base = matplotlib.colormaps[PLOT_CMAP]
    lo, hi = PLOT_CMAP_RANGE
    return ListedColormap(base(np.linspace(lo, hi, 256)), name="hapmotion_print").with_extremes(under="white")


def scale_top(peak: float) -> float:
    """The colour scale's top for a track whose loudest actuator reaches ``peak`` (0..100)."""
    return float(next((t for t in SCALE_TOPS if peak <= t), 100))
