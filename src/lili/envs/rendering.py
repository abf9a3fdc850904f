"""A tiny NumPy rasteriser for the 2D envs' ``rgb_array`` frames (no display, no extra deps)."""

from __future__ import annotations

import numpy as np

__all__ = ["Canvas"]


class Canvas:
    """An RGB image with world coordinates ``xlim`` x ``ylim`` (y up)."""

    def __init__(self, width: int, height: int, xlim: tuple[float, float],
                 ylim: tuple[float, float]) -> None:
        self.image = np.full((height, width, 3), 255, dtype=np.uint8)
        self.xlim, self.ylim = xlim, ylim
        ys, xs = np.mgrid[0:height, 0:width]
        self._x = xlim[0] + (xs + 0.5) / width * (xlim[1] - xlim[0])
        self._y = ylim[1] - (ys + 0.5) / height * (ylim[1] - ylim[0])
        self._px = (xlim[1] - xlim[0]) / width

    def circle(self, center, radius: float, color, fill: bool = True) -> None:
        d = np.hypot(self._x - center[0], self._y - center[1])
        mask = d <= radius if fill else np.abs(d - radius) <= self._px
        self.image[mask] = color

    def rect(self, center, size, color) -> None:
        mask = (np.abs(self._x - center[0]) <= size[0] / 2) & (
            np.abs(self._y - center[1]) <= size[1] / 2)
        self.image[mask] = color

    def vline(self, x: float, color) -> None:
        self.image[np.abs(self._x - x) <= self._px] = color
