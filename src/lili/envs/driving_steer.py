"""Driving with steering (the paper's "Driving (CARLA)"), built on highway-env's road and cars.

The ego must pass an opponent who swerves, suddenly, into the side on which the ego passed last
time. The paper ran this in CARLA; here the two cars are highway-env kinematic bicycle models on
a straight three-lane highway-env road (:mod:`lili.envs.steer_backend`), stepped directly (no
``AbstractEnv``, no pygame drawing). The simulator sits behind :class:`~lili.envs.steer_backend.
SteerBackend`, so a CARLA backend can replace it (``DrivingSteerEnv(backend=...)``).

Rules (the appendix) and the values chosen here (the appendix gives none):

- Road: 3 lanes of 4 m (y = -4 left, 0 middle, +4 right; y points to the driver's right),
  edges at y = -6 and +6. Cars: 5 m x 2 m (highway-env's).
- The ego starts in the middle lane at x = 0 and drives at a constant 20 m/s; it controls only
  the steering angle, ``action[0]`` in [-1, 1] times 0.1 rad (positive = right). 0.1 rad at
  20 m/s is a yaw rate of 0.4 rad/s, a lateral acceleration of 8 m/s^2: a firm but physical
  limit, with which a lane change takes about 1.2 s (6 steps).
- The opponent starts 15 m ahead (centre to centre) in the middle lane at a constant 14 m/s. At
  t = 1.4 s (after step 7) it swerves into its target lane, the left (y = -4) or the right
  (y = +4) lane, with highway-env's lane-change controller at shorter time constants (lateral
  0.4 s, heading 0.15 s, instead of 0.6 s and 0.2 s): about 2.6 m sideways within 0.4 s.
- Why this timing: driving straight, the ego rear-ends the opponent at t = 1.6 s (step 8), so
  it must start steering out of the middle lane by t = 1.2 s (step 7), before the opponent moves
  and before any observation shows where it will go.
  Once the swerve begins, the ego is 1-2 m behind the opponent's rear and 6 m/s faster: it
  cannot cross behind it to the other side. A policy that ignores the past therefore succeeds
  only when it guessed the free side (at best half of the time); one that knows the target
  passes on the other side every time. Passing (rear bumper ahead of the opponent's front
  bumper) takes 20 m of relative travel, about 17 of the 20 steps.
- Control period 0.2 s (5 Hz), H = 20 steps (4 s); the simulation integrates at 20 Hz (4
  substeps per step). At 20 Hz the cars move at most 1 m per integration step and the gap closes
  by 0.3 m, well below the 2 m width and 5 m length of a car, so no collision is stepped over;
  highway-env's own scenarios integrate at 15 Hz.
- An interaction ends early (``terminated``) on a collision between the cars or when a corner
  of the ego's body crosses a road edge (lane violation), so lengths vary from 5 steps (full
  steering lock) to 20. Reward: -1 on that step, 0 on every other step.

The opponent's target lane in interaction i is the side the ego was on at the end of
interaction i - 1: left if the ego's final lateral position y is < 0 (left of the middle lane's
centre line, where the opponent drives until it swerves), right if y >= 0. With
``history`` = N it is the majority of the last N such sides (ties go to the most recent; see
:class:`~lili.envs.partners.MajorityHistory`). The first target is drawn from the seed.

Observation (10 float32): for the ego and then the opponent, position (x, y) / 10 m, velocity
(vx, vy) / 10 m/s over the last integration step (slip included) and yaw rate in rad/s (positive
turning right). The scales keep every entry within a few units. The target lane never appears.

``info["strategy"]`` = one-hot of the target lane [left, right], ``info["strategy_id"]`` = 0
(left) or 1 (right). ``info["collision"]`` and ``info["off_road"]`` flag the two ways an
interaction ends early. ``info["success"]`` (last step) = the interaction ran all H steps
without a collision or a lane violation and ended with the ego past the opponent (its centre at
least one car length, 5 m, ahead of the opponent's).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from lili.envs.core import RepeatedInteractionEnv
from lili.envs.partners import MajorityHistory, check_partner_options
from lili.envs.steer_backend import CarState, Scenario, SimState, SteerBackend

__all__ = ["DrivingSteerEnv", "SteerPartner", "draw", "MAX_STEER", "SCENARIO", "HORIZON"]

SCENARIO = Scenario()
MAX_STEER = 0.1  # rad, the steering angle at action +-1
HORIZON = 20
POS_SCALE, VEL_SCALE = 10.0, 10.0
LEFT, RIGHT = 0, 1

# Generous bounds: positions reach about 9.5 (95 m) in 20 steps and the cars stay within about
# 0.7 (7 m) of the road's centre line before an episode ends; values are clipped into them.
_CAR_LOW = np.array([-5.0, -3.0, -5.0, -5.0, -10.0], dtype=np.float32)
_CAR_HIGH = np.array([30.0, 3.0, 5.0, 5.0, 10.0], dtype=np.float32)


class SteerPartner:
    """Swerves into the side the ego was on at the end of the last interaction.

    Majority over the last ``history`` interactions; the strategy is a one-hot [left, right].
    """

    strategy_space = spaces.Box(0.0, 1.0, shape=(2,), dtype=np.float32)

    def __init__(self, history: int = 1) -> None:
        check_partner_options(0.0, history)
        self.votes = MajorityHistory(history)
        self.side = LEFT

    def reset(self, rng: np.random.Generator) -> None:
        self.votes.clear()
        self.side = int(rng.integers(0, 2))

    def strategy(self) -> np.ndarray:
        onehot = np.zeros(2, dtype=np.float32)
        onehot[self.side] = 1.0
        return onehot

    def strategy_id(self) -> int | None:
        return self.side

    def update(self, outcome: int, rng: np.random.Generator) -> None:
        """``outcome`` is the ego's final side: 0 (left) or 1 (right)."""
        self.side = int(self.votes.push(int(outcome)))


def _car_obs(car: CarState) -> np.ndarray:
    return np.array([car.position[0] / POS_SCALE, car.position[1] / POS_SCALE,
                     car.velocity[0] / VEL_SCALE, car.velocity[1] / VEL_SCALE, car.yaw_rate])


class DrivingSteerEnv(RepeatedInteractionEnv):
    """``lili/DrivingSteer-v0``: steer past an opponent that blocks your last side.

    See the module docstring for the rules. ``backend`` is the simulator (default: a new
    :class:`~lili.envs.steer_backend.HighwayBackend`); anything implementing
    :class:`~lili.envs.steer_backend.SteerBackend` works.
    """

    strategy_names = ("left", "right")

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 5}

    def __init__(self, history: int = 1, backend: SteerBackend | None = None,
                 render_mode: str | None = None) -> None:
        super().__init__(render_mode)
        self.partner = SteerPartner(history)
        if backend is None:
            from lili.envs.steer_backend import HighwayBackend

            backend = HighwayBackend()
        elif not isinstance(backend, SteerBackend):
            raise ValueError(
                f"backend={backend!r} is invalid; allowed: None (highway-env) or an object with "
                f"reset(scenario, target_lane) and step(steer) (lili.envs.steer_backend."
                f"SteerBackend)")
        self.backend = backend
        self.scenario = SCENARIO
        self.horizon = HORIZON
        self.observation_space = spaces.Box(np.tile(_CAR_LOW, 2), np.tile(_CAR_HIGH, 2),
                                            dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(1,), dtype=np.float32)
        self.state: SimState | None = None

    def _obs(self) -> np.ndarray:
        obs = np.concatenate([_car_obs(self.state.ego), _car_obs(self.state.opponent)])
        return np.clip(obs, self.observation_space.low, self.observation_space.high).astype(
            np.float32)

    def _begin(self) -> np.ndarray:
        target = 0 if self.partner.side == LEFT else self.scenario.n_lanes - 1
        self.state = self.backend.reset(self.scenario, target)
        return self._obs()

    def _step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool]:
        steer = MAX_STEER * float(np.clip(action[0], -1.0, 1.0))
        self.state = self.backend.step(steer)
        failed = self.state.collided or self.state.off_road
        return self._obs(), -1.0 if failed else 0.0, failed

    def _outcome(self) -> int:
        return LEFT if self.state.ego.position[1] < 0 else RIGHT

    def _success(self) -> bool:
        st = self.state
        if st.collided or st.off_road or self.t < self.horizon:
            return False
        return bool(st.ego.position[0] - st.opponent.position[0] >= self.scenario.car_length)

    def _info(self) -> dict[str, Any]:
        info = super()._info()
        st = self.state
        info["collision"] = bool(st is not None and st.collided)
        info["off_road"] = bool(st is not None and st.off_road)
        return info

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array" or self.state is None:
            return None
        return draw(self.scenario, self.state)


def draw(sc: Scenario, state: SimState, px_per_m: float = 8.0) -> np.ndarray:
    """A top view (driving up the image) of the road around the ego and both cars."""
    from lili.envs.rendering import Canvas

    left, right = sc.road_edges
    margin = 2.0
    ego_x = float(state.ego.position[0])
    behind, ahead = 12.0, 36.0
    width = int(round((right - left + 2 * margin) * px_per_m))
    height = int(round((behind + ahead) * px_per_m))
    # Canvas x is the road's lateral y (right on screen = driver's right), canvas y the road's x.
    canvas = Canvas(width, height, (left - margin, right + margin),
                    (ego_x - behind, ego_x + ahead))
    # Pixel centres in world coordinates: lat across the image, lon up it.
    cols = (np.arange(width) + 0.5) / width
    rows = (np.arange(height) + 0.5) / height
    lat = (left - margin + cols * (right - left + 2 * margin))[None, :]
    lon = (ego_x + ahead - rows * (behind + ahead))[:, None]
    lat, lon = np.broadcast_arrays(lat, lon)
    canvas.image[:] = (110, 170, 90)
    canvas.image[(lat >= left) & (lat <= right)] = (90, 90, 90)
    for edge in (left, right):
        canvas.vline(edge, (240, 240, 240))
    for lane in range(1, sc.n_lanes):
        y = left + lane * sc.lane_width
        dashed = (np.abs(lat - y) <= 0.12) & (np.mod(lon, 6.0) < 3.0)
        canvas.image[dashed] = (230, 230, 230)
    for car, color in ((state.opponent, (220, 60, 60)), (state.ego, (40, 90, 220))):
        # Rotate the pixel grid into the car's frame: along = its heading, across = its right.
        dx, dy = lon - car.position[0], lat - car.position[1]
        c, s = np.cos(car.heading), np.sin(car.heading)
        along, across = c * dx + s * dy, -s * dx + c * dy
        body = (np.abs(along) <= sc.car_length / 2) & (np.abs(across) <= sc.car_width / 2)
        canvas.image[body] = color
        windshield = body & (along > sc.car_length / 4) & (along < sc.car_length * 0.4)
        canvas.image[windshield] = (200, 220, 240)
    return canvas.image
