"""Write rendered frames to an animated GIF (Pillow ships with matplotlib; no ffmpeg needed)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["write_video"]


def write_video(frames: list[np.ndarray], path: str | Path, fps: int = 10) -> Path:
    """Save ``frames`` (HxWx3 uint8) to ``path``; only ``.gif`` is supported."""
    from PIL import Image

    path = Path(path)
    if path.suffix.lower() != ".gif":
        raise ValueError(f"video path {str(path)!r} is not supported; allowed: a .gif file")
    if not frames or any(f is None for f in frames):
        raise ValueError("no frames to write: make the env with render_mode='rgb_array'")
    path.parent.mkdir(parents=True, exist_ok=True)
    images = [Image.fromarray(np.asarray(f, np.uint8)) for f in frames]
    images[0].save(path, save_all=True, append_images=images[1:], duration=int(1000 / fps),
                   loop=0)
    return path
