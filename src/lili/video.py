"""Animated GIFs of interactions (``lili eval --video``), each frame labelled.

Pillow ships with matplotlib, so no ffmpeg is needed. :class:`LabelledFrames` wraps the env that
is evaluated: its ``render()`` adds a strip above the env's frame with the interaction index,
the partner's strategy (and ``strategy_id`` where the env defines one) and the return so far,
read from the env's own ``reset``/``step`` results, so the evaluation loop needs no change.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

__all__ = ["write_video", "check_video_path", "LabelledFrames", "frame_label"]

_LINE_HEIGHT = 12  # pixels per line of Pillow's default bitmap font (11 px glyphs)


def check_video_path(path: str | Path) -> Path:
    """``path`` as a Path, or ValueError naming it: only a ``.gif`` file in an existing folder.

    Checked before anything is evaluated or written, and no folder is created: a typo in the
    folder should fail, not leave new folders behind.
    """
    p = Path(path)
    if p.suffix.lower() != ".gif":
        raise ValueError(f"video path {str(p)!r} is not supported; allowed: a .gif file")
    if p.is_dir():
        raise ValueError(f"video path {str(p)!r} is a folder; allowed: a .gif file")
    parent = p.parent
    if not parent.is_dir():
        what = "is a file" if parent.exists() else "does not exist"
        raise ValueError(f"video path {str(p)!r} is invalid: its folder {str(parent)!r} {what}; "
                         "allowed: a .gif file in an existing folder")
    return p


def write_video(frames: list[np.ndarray], path: str | Path, fps: int = 10) -> Path:
    """Save ``frames`` (HxWx3 uint8) to ``path`` (see :func:`check_video_path`)."""
    from PIL import Image

    path = check_video_path(path)
    if not frames or any(f is None for f in frames):
        raise ValueError("no frames to write: make the env with render_mode='rgb_array'")
    images = [Image.fromarray(np.asarray(f, np.uint8)) for f in frames]
    images[0].save(path, save_all=True, append_images=images[1:], duration=int(1000 / fps),
                   loop=0)
    return path


def frame_label(interaction: int, strategy: Any, strategy_id: int | None,
                ret: float) -> list[str]:
    """The label lines of one frame: interaction index, strategy (and id), return so far."""
    z = np.asarray(strategy, dtype=np.float64).ravel()
    line = "strategy [" + " ".join(f"{v:.2g}" for v in z) + "]"
    if strategy_id is not None and strategy_id != -1:
        line += f" id {int(strategy_id)}"
    return [f"interaction {int(interaction)}", line, f"return {ret:.2f}"]


def _draw_label(frame: np.ndarray, lines: list[str]) -> np.ndarray:
    from PIL import Image, ImageDraw

    frame = np.asarray(frame, np.uint8)
    strip = np.zeros((_LINE_HEIGHT * len(lines) + 4, frame.shape[1], 3), np.uint8)
    image = Image.fromarray(strip)
    draw = ImageDraw.Draw(image)
    for n, text in enumerate(lines):
        draw.text((3, 2 + n * _LINE_HEIGHT), text, fill=(255, 255, 255))
    return np.concatenate([np.asarray(image), frame[..., :3]], axis=0)


class LabelledFrames(gym.Wrapper):
    """An env whose ``render()`` frames carry :func:`frame_label`'s lines above the picture.

    The labels describe the state the frame shows: the interaction of the last ``reset``, its
    strategy from ``info``, and the rewards summed over this interaction's steps so far.
    """

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.interaction, self.strategy, self.strategy_id = 0, np.zeros(0), None
        self.ret = 0.0

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        obs, info = self.env.reset(**kwargs)
        self.ret = 0.0
        self._note(info)
        return obs, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        obs, reward, terminated, truncated, info = self.env.step(action)
        self.ret += float(reward)
        self._note(info)
        return obs, reward, terminated, truncated, info

    def _note(self, info: dict[str, Any]) -> None:
        self.interaction = int(info.get("interaction", self.interaction))
        self.strategy = info.get("strategy", self.strategy)
        self.strategy_id = info.get("strategy_id", self.strategy_id)

    def label(self) -> list[str]:
        """The lines the next rendered frame carries."""
        return frame_label(self.interaction, self.strategy, self.strategy_id, self.ret)

    def render(self) -> Any:
        frame = self.env.render()
        return None if frame is None else _draw_label(frame, self.label())
