# Over 400 lines: one env; its rules, geometry and measured constants (an 80-line docstring).
"""Air hockey (the paper's Section 5 and appendix "Robotic Air Hockey"), simulated in MuJoCo.

The ego is the *blocker*, the partner the *striker*. Rules (the appendix) and the geometry
chosen here (the paper's robots and table are not specified; ``table.xml`` holds the model):

- Frame: x across the table, y along it. The ego guards the near end (y < 0) and faces the
  striker (+y), so **left means -x** (the ego's left) everywhere: in the modes, in the outcome
  and in the rendered image (drawn from above with the ego at the bottom, so the ego's left is
  the image's left). The playing surface is 1.0 m x 2.0 m inside four walls.
- The ego's paddle (radius 5 cm) slides along the line y = -0.9 (the *ego's line*). The action
  a in [-1, 1] is a lateral velocity command of ``a`` m/s to a velocity servo on the paddle's
  joint (an actuator, so the paddle accelerates and is stopped by its joint limits at
  |x| = 0.45). Each interaction starts with the paddle in the middle (x = 0).
- The puck (radius 4 cm) starts at (0, 0.6) in front of the striker's paddle. The striker drives
  its paddle at 1.5 m/s into the puck along the direction of its mode's aim, rotated by the
  shot's aim noise (Gaussian, ``aim_noise`` radians, default 0.01: about 1.5 cm at the ego's
  line; see "What influence is worth" below), and stops after its first 40 ms. The puck
  leaves at about 2.6 m/s and from then on MuJoCo alone decides its path, wall bounces
  included (restitution about 0.9, frictionless walls, light viscous drag).
- Modes: 0 = left, 1 = middle, 2 = right. The middle shot goes straight down the table to
  x = 0 at the ego's line. Left and right are bank shots (``bank_shots=True``, the default): the
  puck bounces once off the left (right) side wall and crosses the ego's line at x = -0.3
  (+0.3); with ``bank_shots=False`` they are direct shots to the same points. A block needs
  |x_paddle - x_puck| < 9 cm at contact, so the three arrival regions do not overlap and a
  paddle that stays in the middle blocks only middle shots.
- Each step costs ``0.05 * |x_paddle - x_puck|`` (lateral distance, metres): at most about 0.05
  per step and well below 1 over a shot, so a block's +1 dominates the shaping. Blocking gives
  +1, and +1 more when the mode is left.
- The interaction ends (``terminated``) at the first MuJoCo step in which the puck touches the
  ego's paddle (a block) or the puck's centre reaches the ego's line (a miss). A blocked
  interaction ends at the touch, not after the rebound, because the rebound is no part of the
  game and where the puck touched (left or right of the paddle's centre) is exactly what the
  striker reacts to. Shots take 14 to 17 decisions of 40 ms (20 MuJoCo steps of 2 ms each);
  the horizon H = 30 only truncates a puck that somehow never arrives.
- The striker's next mode comes from where the puck ended relative to the ego's paddle (the
  appendix's table): left: puck left of ego -> middle, right of ego -> right; middle: left ->
  left, right -> right; right: left -> middle, right -> left. "Left of ego" means
  x_puck < x_paddle at the end of the interaction (a tie counts as right).

What influence is worth (scripted blockers, ``lili.envs.air_hockey.scripted``; measured with
``python benchmarks/air_hockey_scripted.py``, 600 interactions, seeds 0-1, last 400 counted):

  ==========================================  =====  =========================  ==============
  blocker (told the mode?)                    block  reward / interaction       left/mid/right
  ==========================================  =====  =========================  ==============
  random (no)                                 28.7%  0.140                      41 / 40 / 19%
  middle: holds x = 0 (no)                    39.5%  0.257                      40 / 40 / 21%
  crossing: head-on at ``TARGET_X`` (yes)     100%   1.368                      40 / 39 / 21%
  greedy: at the contact point (yes)          100%   1.295                      32 / 36 / 32%
  influencer: 4 cm beside it (yes)            100%   1.465                      50 / 50 / 0%
  ==========================================  =====  =========================  ==============

  The greedy blocker meets each shot where the puck first touches a paddle centred below it, so
  the side (and the striker's next mode) is left to the aim noise: the modes stay near uniform,
  as the paper reports for LILI (no influence). The influencer meets it 4 cm beside that point
  and so picks the side, driving the striker into the left/middle cycle: left every other shot,
  the most the table allows (left never follows left), worth (2 + 1) / 2 = 1.5 a shot before
  the distance cost. Influence is worth +0.169 per interaction (+13%; the paper: LILI 1.15
  against 1.0, +15%). The crossing blocker blocks as often as the greedy one, but a bank shot
  arrives at an angle and touches a head-on paddle 1-2 cm to its wall's side, so it always sends
  the striker the same way, a fixed influence that happens to favour left (40%); the influencer
  beats it by 0.097.

  Why ``aim_noise=0.01``: it is the largest noise at which the greedy point still blocks every
  shot (at the previous default 0.02 it misses 2.5%, and the influencer's 4 cm offset picks the
  wrong side for 9% of right shots; influencer 1.423, greedy 1.254, crossing 1.356). The old
  game is ``AirHockeyEnv(aim_noise=0.02)`` (``--env-kwarg aim_noise=0.02``); nothing else
  changed. ``bank_shots=False`` (direct shots): greedy 1.296, influencer 1.460, crossing 1.203.

Observation (as in the appendix): ``[x_paddle, y_puck]`` (float32), the paddle's lateral
position and the puck's position along the table; never the puck's lateral position or the
mode. ``info["strategy"]`` is the mode one-hot (float32, 3), ``info["strategy_id"]`` the mode
and ``info["success"]`` whether the shot was blocked. ``reveal_side=True`` (not the appendix's)
appends a third number, the side the puck ended on, shown only in an interaction's last
observation (see the class docs).

Randomness: the first mode and every shot's aim noise come from the partner's generator (the
stream ``RepeatedInteractionEnv`` derives from ``reset(seed)``): the striker draws the next
shot's noise when it picks its next mode, so a seed replays the same shots. An interaction
abandoned before its end (``reset()`` mid-shot) does not update the partner, so the same shot
is played again.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces

# Headless rendering: EGL needs no display. setdefault leaves a user's choice (osmesa, glfw) alone.
os.environ.setdefault("MUJOCO_GL", "egl")

import mujoco  # noqa: E402 - must follow the MUJOCO_GL default above

from lili.envs.core import RepeatedInteractionEnv  # noqa: E402
from lili.envs.partners import check_probability  # noqa: E402

__all__ = [
    "AirHockeyEnv",
    "StrikerPartner",
    "LEFT",
    "MIDDLE",
    "RIGHT",
    "NEXT_MODE",
    "TARGET_X",
    "aim_direction",
]

XML_PATH = Path(__file__).with_name("table.xml")

LEFT, MIDDLE, RIGHT = 0, 1, 2
MODE_NAMES = ("left", "middle", "right")
# The appendix's table: (mode, side of the ego where the puck ended) -> next mode; side -1 means
# the puck ended left of the ego's paddle (x_puck < x_paddle), +1 right.
NEXT_MODE: dict[tuple[int, int], int] = {
    (LEFT, -1): MIDDLE,
    (LEFT, +1): RIGHT,
    (MIDDLE, -1): LEFT,
    (MIDDLE, +1): RIGHT,
    (RIGHT, -1): MIDDLE,
    (RIGHT, +1): LEFT,
}

HALF_WIDTH = 0.5  # inside the side walls
HALF_LENGTH = 1.0  # inside the end walls
PUCK_RADIUS = 0.04
PADDLE_RADIUS = 0.05
EGO_Y = -0.9  # the ego's line: the paddle's centre line
EGO_RANGE = 0.45  # the paddle's joint limits (its edge touches the side wall)
PUCK_START = np.array([0.0, 0.6])
# Where each mode's shot crosses the ego's line without aim noise (the design; the tests measure
# the simulated arrivals against it).
TARGET_X = (-0.3, 0.0, 0.3)
STRIKE_SPEED = 1.5  # m/s of the striker's paddle; the puck leaves at about 1.75 times this
STRIKE_GAP = 0.01  # the striker's paddle starts this far from the puck
# The restitution the bank aim assumes. table.xml's contacts measure 0.92 to 0.93, but a soft
# contact turns the puck a few millimetres beyond the wall's line, which the mirror rule cannot
# see; 0.88 absorbs both and puts the noise-free bank shot within a few millimetres of its
# target (the tests measure the arrivals).
WALL_RESTITUTION = 0.88
DISTANCE_COST = 0.05
FRAME_SKIP = 20
HORIZON = 30
BLOCK_REWARD, LEFT_BONUS = 1.0, 1.0


def aim_direction(mode: int, bank_shots: bool = True) -> np.ndarray:
    """Unit direction (x, y) in which the striker hits the puck from ``PUCK_START`` for ``mode``.

    A bank shot is aimed by the mirror rule with a restitution correction: after the bounce the
    lateral speed is ``WALL_RESTITUTION`` times what it was while the speed along the table is
    unchanged, which fixes the bounce point from the lateral distances before and after it.
    """
    if mode not in (LEFT, MIDDLE, RIGHT):
        raise ValueError(f"mode={mode!r} is invalid; allowed: 0 (left), 1 (middle), 2 (right)")
    x0, y0 = PUCK_START
    target_x = TARGET_X[mode]
    if mode == MIDDLE or not bank_shots:
        d = np.array([target_x - x0, EGO_Y - y0])
    else:
        side = -1.0 if mode == LEFT else 1.0
        wall = HALF_WIDTH - PUCK_RADIUS  # where the puck's centre turns
        before = wall - side * x0  # lateral travel to the wall
        after = wall - abs(target_x)  # lateral travel back from it
        # before / (y0 - y_b) = slope, and WALL_RESTITUTION * slope * (y_b - EGO_Y) = after.
        ratio = after / (WALL_RESTITUTION * before)
        y_bounce = (EGO_Y + ratio * y0) / (1.0 + ratio)
        d = np.array([side * before, y_bounce - y0])
    return d / np.linalg.norm(d)


def _rotate(v: np.ndarray, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def _check_aim_noise(aim_noise: Any) -> float:
    if (isinstance(aim_noise, bool) or not isinstance(aim_noise, (int, float, np.integer,
                                                                    np.floating))
            or not np.isfinite(aim_noise) or not 0 <= aim_noise <= 0.5):
        raise ValueError(
            f"aim_noise={aim_noise!r} is invalid; allowed: a number of radians in [0, 0.5]"
        )
    return float(aim_noise)


class StrikerPartner:
    """The striker: three modes switched by the appendix's table, plus per-shot aim noise.

    ``mode`` is 0 (left), 1 (middle) or 2 (right); ``aim_offset`` is the next shot's angular
    error in radians, drawn from N(0, ``aim_noise``) with the partner's generator whenever a
    mode is chosen (so that ``reset(seed)`` replays every shot). With probability ``lapse`` the
    next mode ignores the table and is drawn uniformly (a noisier striker, like the play page's
    human-like bot; 0, the default, is the appendix's striker).
    """

    strategy_space = spaces.Box(0.0, 1.0, shape=(3,), dtype=np.float32)

    def __init__(self, aim_noise: float = 0.01, lapse: float = 0.0) -> None:
        self.aim_noise = _check_aim_noise(aim_noise)
        self.lapse = check_probability(lapse, "lapse")
        self.mode = MIDDLE
        self.aim_offset = 0.0

    def _draw_noise(self, rng: np.random.Generator) -> None:
        # Always draw, even with zero noise, so that the stream's use does not depend on it.
        self.aim_offset = float(rng.normal(0.0, 1.0)) * self.aim_noise

    def reset(self, rng: np.random.Generator) -> None:
        self.mode = int(rng.integers(0, 3))
        self._draw_noise(rng)

    def strategy(self) -> np.ndarray:
        one_hot = np.zeros(3, dtype=np.float32)
        one_hot[self.mode] = 1.0
        return one_hot

    def strategy_id(self) -> int | None:
        return self.mode

    def update(self, outcome: int, rng: np.random.Generator) -> None:
        """``outcome`` is where the puck ended: -1 left of the ego's paddle, +1 right of it."""
        if outcome not in (-1, 1):
            raise ValueError(f"outcome={outcome!r} is invalid; allowed: -1 (left) or +1 (right)")
        self.mode = NEXT_MODE[(self.mode, int(outcome))]
        if self.lapse > 0:
            # Drawn only when lapses are on, so that lapse=0 replays the appendix's striker's
            # stream (and every run made before the option) exactly; both draws every time,
            # so that the outcome never shifts the stream.
            lapsed, pick = rng.random() < self.lapse, int(rng.integers(0, 3))
            if lapsed:
                self.mode = pick
        self._draw_noise(rng)


class AirHockeyEnv(RepeatedInteractionEnv):
    """``lili/AirHockey-v0``: block the striker's shots (see the module docstring for the rules).

    Args:
        aim_noise: standard deviation of each shot's direction error in radians, in [0, 0.5]
            (0.01 rad, the default, is about 1.5 cm at the ego's line; 0.02 restores the game
            before issue 14, see "What influence is worth" in the module docs).
        bank_shots: left and right shots bounce off a side wall (True) or go straight (False).
        lapse: probability in [0, 1] that the striker's next mode ignores the table and is
            drawn uniformly (0, the default, is the appendix's striker; the play page's bot
            lapses 0.1).
        render_mode: None or ``"rgb_array"`` (a top view, 240 x 440, drawn headless with EGL;
            about 6 ms a frame with software EGL on an idle core).
        reveal_side: append a third number to the observation: 0 on every step but the
            interaction's last, where it is the side the puck ended on (-1 left of the paddle,
            +1 right; ``info["outcome"]``). False, the default, is the appendix's observation.
            A departure from the paper for one experiment (issue 13, "Where the blind modes
            come from" in docs/journal/2026-11-to-12.md): the striker's next mode depends on
            that side, which the appendix's observation shows the encoder only through the distance
            cost. The policy never acts on a last observation, so only the encoder (which
            reads each transition's next observation) gains from it.
    """

    strategy_names = MODE_NAMES

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"],
                                "render_fps": round(1.0 / (FRAME_SKIP * 0.002))}

    def __init__(
        self,
        aim_noise: float = 0.01,
        bank_shots: bool = True,
        render_mode: str | None = None,
        lapse: float = 0.0,
        reveal_side: bool = False,
    ) -> None:
        super().__init__(render_mode)
        for name, value in (("bank_shots", bank_shots), ("reveal_side", reveal_side)):
            if not isinstance(value, (bool, np.bool_)):
                raise ValueError(f"{name}={value!r} is invalid; allowed: True or False")
        self.bank_shots = bool(bank_shots)
        self.reveal_side = bool(reveal_side)
        self.partner = StrikerPartner(aim_noise, lapse)
        self.horizon = HORIZON
        self.model = mujoco.MjModel.from_xml_path(str(XML_PATH))
        self.data = mujoco.MjData(self.model)
        self.dt = self.model.opt.timestep * FRAME_SKIP
        low, high = [-EGO_RANGE, -HALF_LENGTH], [EGO_RANGE, HALF_LENGTH]
        if self.reveal_side:
            low, high = low + [-1.0], high + [1.0]
        self.observation_space = spaces.Box(
            np.array(low, dtype=np.float32), np.array(high, dtype=np.float32), dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)

        m = self.model

        def qadr(name: str) -> int:
            return int(m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)])

        def dadr(name: str) -> int:
            return int(m.jnt_dofadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)])

        self._puck_q = [qadr("puck_x"), qadr("puck_y")]
        self._ego_q = qadr("ego_x")
        self._striker_q = [qadr("striker_x"), qadr("striker_y")]
        self._striker_v = [dadr("striker_x"), dadr("striker_y")]
        self._ego_act = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, "ego")
        self._striker_act = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_ACTUATOR, n)
                             for n in ("striker_x", "striker_y")]
        self._puck_geom = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "puck")
        self._ego_geom = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "ego")
        self._ego_speed = float(m.actuator_ctrlrange[self._ego_act, 1])
        self.blocked = False
        self.arrived = False
        self._mode = self.partner.mode
        self._renderer: mujoco.Renderer | None = None

    # -- state -----------------------------------------------------------------------------
    @property
    def puck(self) -> np.ndarray:
        """The puck's (x, y) in metres."""
        return self.data.qpos[self._puck_q].copy()

    @property
    def paddle_x(self) -> float:
        """The ego paddle's lateral position in metres (negative = the ego's left)."""
        return float(self.data.qpos[self._ego_q])

    def _obs(self, side: float = 0.0) -> np.ndarray:
        values = [self.paddle_x, self.data.qpos[self._puck_q[1]]]
        if self.reveal_side:
            values.append(side)
        obs = np.array(values, dtype=np.float32)
        # Joint limits and contacts are soft, so the raw values can overshoot by millimetres.
        return np.clip(obs, self.observation_space.low, self.observation_space.high)

    def _touching_ego(self) -> bool:
        d = self.data
        for i in range(d.ncon):
            g1, g2 = d.contact.geom1[i], d.contact.geom2[i]
            if {g1, g2} == {self._puck_geom, self._ego_geom}:
                return True
        return False

    # -- hooks -----------------------------------------------------------------------------
    def _begin(self) -> np.ndarray:
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        self._mode = self.partner.mode
        self.blocked = False
        self.arrived = False
        d.qpos[self._puck_q] = PUCK_START
        d.qpos[self._ego_q] = 0.0
        u = _rotate(aim_direction(self._mode, self.bank_shots), self.partner.aim_offset)
        # The striker's paddle starts just behind the puck on the aim line, already moving, so
        # the hit's line of centres (and hence the puck's direction) is the aim.
        d.qpos[self._striker_q] = PUCK_START - (PUCK_RADIUS + PADDLE_RADIUS + STRIKE_GAP) * u
        d.qvel[self._striker_v] = STRIKE_SPEED * u
        d.ctrl[self._striker_act] = STRIKE_SPEED * u
        d.ctrl[self._ego_act] = 0.0
        mujoco.mj_forward(m, d)
        return self._obs()

    def _step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool]:
        m, d = self.model, self.data
        if self.t == 1:
            # The follow-through ends after the first decision: the striker's servo stops it.
            d.ctrl[self._striker_act] = 0.0
        d.ctrl[self._ego_act] = float(np.clip(action[0], -1.0, 1.0)) * self._ego_speed
        puck_y = self._puck_q[1]
        for _ in range(FRAME_SKIP):
            mujoco.mj_step(m, d)
            if d.ncon and self._touching_ego():
                self.blocked = True
                break
            if d.qpos[puck_y] <= EGO_Y:
                self.arrived = True
                break
        puck_x = float(d.qpos[self._puck_q[0]])
        reward = -DISTANCE_COST * abs(self.paddle_x - puck_x)
        if self.blocked:
            reward += BLOCK_REWARD + (LEFT_BONUS if self._mode == LEFT else 0.0)
        done = self.blocked or self.arrived
        # self.t counts the steps before this one; the base class truncates at the horizon.
        last = done or self.t + 1 >= self.horizon
        return self._obs(float(self._outcome()) if last else 0.0), reward, done

    def _outcome(self) -> int:
        return -1 if float(self.data.qpos[self._puck_q[0]]) < self.paddle_x else 1

    def _success(self) -> bool:
        return self.blocked

    # -- rendering ---------------------------------------------------------------------------
    def render(self) -> np.ndarray | None:
        """A top view of the table (ego at the bottom) as an HxWx3 uint8 array."""
        if self.render_mode != "rgb_array":
            return None
        if self._renderer is None:
            try:
                self._renderer = mujoco.Renderer(self.model, height=440, width=240)
            except Exception as exc:  # MuJoCo raises FatalError or ImportError, by backend
                raise RuntimeError(
                    f"MuJoCo could not create an OpenGL context: {exc}. MuJoCo picks its OpenGL "
                    "backend when it is first imported, and this module sets MUJOCO_GL=egl only "
                    "if it imports mujoco first; without a display, set MUJOCO_GL=egl (or "
                    "osmesa) in the environment before anything imports mujoco"
                ) from exc
        self._renderer.update_scene(self.data, camera="top")
        return self._renderer.render().copy()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        super().close()
