"""One game on the air hockey table: the person's (or bot's) shots against the trained blocker.

A :class:`GameSession` owns its own env (the training env, with :class:`AimedStriker` in place
of the robot striker), the blocker's acting state and the session's record. :meth:`shoot` plays
one shot and yields the table's state after every decision step, so the server can stream it
and the bot can ignore it. A shot counts only once it is recorded: when its row cannot be
written the game ends there (:attr:`GameSession.ended`), because the blocker has already seen
a shot the record would lack.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import mujoco

from lili.play.policy import Blocker, ScriptedBlocker, interaction_steps, make_play_env
from lili.play.probe import ModeProbe
from lili.play.record import RecordError, SessionRecord
from lili.play.striker import MODE_NAMES, AimedStriker

__all__ = ["GameSession", "make_play_env"]


class GameSession:
    """A game of ``shots`` shots; see the module docstring."""

    def __init__(self, blocker: Blocker | ScriptedBlocker, env_kwargs: dict[str, Any], shots: int,
                 record: SessionRecord | None = None, probe: ModeProbe | None = None,
                 seed: int = 0) -> None:
        self.env = blocker.wrap(make_play_env(env_kwargs))
        self.table = self.env.unwrapped
        self.striker = AimedStriker(self.table.bank_shots)
        self.table.partner = self.striker
        self.game = blocker.new_game()
        self.shots, self.seed = int(shots), int(seed)
        self.record, self.probe = record, probe
        self.shot = 0
        self.ended: str | None = None  # why the game ended before its last shot
        self.blocks = [0, 0, 0]
        self.by_mode = [0, 0, 0]
        # Wall time of each decision step (action + physics) and of each latent update.
        self.step_seconds: list[float] = []
        self.latent_seconds: list[float] = []
        m = self.table.model
        self._striker_q = [int(m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, n)])
                           for n in ("striker_x", "striker_y")]

    @property
    def over(self) -> bool:
        """All shots of the game have been played, or it ended early (:meth:`end`)."""
        return self.shot >= self.shots or self.ended is not None

    def end(self, reason: str) -> None:
        """End the game before its last shot, for ``reason`` (shown to the player)."""
        self.ended = reason

    def state(self, t: int) -> dict[str, Any]:
        """The table as the page draws it (metres, the env's frame)."""
        puck = self.table.puck
        striker = self.table.data.qpos[self._striker_q]
        return {"type": "frame", "shot": self.shot + 1, "t": t,
                "puck": [round(float(puck[0]), 4), round(float(puck[1]), 4)],
                "paddle": round(self.table.paddle_x, 4),
                "striker": [round(float(striker[0]), 4), round(float(striker[1]), 4)]}

    def score(self) -> dict[str, Any]:
        """Blocks (the robot's), goals (the striker's: shots it did not block) and shots so far,
        in total and by the shots' modes (left, middle, right)."""
        return {"shots": self.shot, "blocks": sum(self.blocks),
                "goals": self.shot - sum(self.blocks), "of": self.shots,
                "by_mode": {MODE_NAMES[m]: [self.blocks[m], self.by_mode[m]] for m in range(3)}}

    def belief(self) -> dict[str, Any] | None:
        """What the blocker expects of the next shot: None before the first shot (z^1 = 0 holds
        no information, whatever a probe reads off it) and for an agent without a latent."""
        if self.probe is None or self.shot == 0:
            return None
        return self.probe.belief(self.game.latent)

    def shoot(self, aim: float) -> Iterator[dict[str, Any]]:
        """Play one shot aimed at ``aim`` radians; yield frames, then the result message."""
        if self.over:
            raise ValueError(f"the game is over ({self.shot} of {self.shots} shots played)")
        mode = self.striker.aim(aim)
        if self.shot == 0:
            obs, first_info = self.env.reset(seed=self.seed)
        else:
            obs, first_info = self.env.reset()
        self.game.begin(first_info)
        first_obs, ret, t, info = obs, 0.0, 0, {}
        yield self.state(0)
        start = time.perf_counter()
        for step in interaction_steps(self.env, self.game, obs):
            t, reward, _done, info = step
            self.step_seconds.append(time.perf_counter() - start)
            ret += reward
            yield self.state(t)
            start = time.perf_counter()
        blocked = bool(info.get("success", False))
        puck_x, paddle_x = float(self.table.puck[0]), self.table.paddle_x
        # Every air hockey interaction starts from the same observation, so this interaction's
        # first one stands in for the next's (it feeds training targets only, not the latent).
        start = time.perf_counter()
        self.game.end_interaction(first_obs)
        self.latent_seconds.append(time.perf_counter() - start)
        row = {"shot": self.shot + 1, "aim": round(float(aim), 5), "mode": MODE_NAMES[mode],
               "blocked": int(blocked), "reward": round(float(ret), 5),
               "puck_x": round(puck_x, 4), "paddle_x": round(paddle_x, 4)}
        if self.record is not None:
            try:
                self.record.write(row)
            except RecordError as e:
                self.end(str(e))
                raise
        self.shot += 1
        self.by_mode[mode] += 1
        self.blocks[mode] += int(blocked)
        yield {"type": "result", **row, "side": self.striker.last_outcome, "steps": t,
               "score": self.score(), "belief": self.belief(), "done": self.over}

    def play(self, aim: float) -> dict[str, Any]:
        """Play one shot without streaming; return its result message."""
        *_, result = self.shoot(aim)
        return result

    def close(self) -> None:
        self.env.close()
