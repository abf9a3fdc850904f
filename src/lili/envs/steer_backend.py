"""The simulator behind ``lili/DrivingSteer-v0``: one small interface and a highway-env backend.

The env (:mod:`lili.envs.driving_steer`) talks to the simulator only through
:class:`SteerBackend`: ``reset(scenario, target_lane)`` places the two cars and ``step(steer)``
advances one control period and reports both cars' states, whether they collided and whether the
ego left the road. Another simulator (a CARLA client, say) implements the same two methods and
plugs into the env with ``DrivingSteerEnv(backend=...)``; neither the env nor the agents change.

Coordinates (shared by every backend): x along the road (the direction of travel), y to the
driver's right, in metres, with the origin on the centre line of the middle lane at the ego's
start. Lanes are numbered 0, 1, ... from left (most negative y) to right, as in highway-env.
Positive steering turns right (towards +y).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["CarState", "HighwayBackend", "Scenario", "SimState", "SteerBackend"]


@dataclass(frozen=True)
class Scenario:
    """Road geometry, the two cars' start and speeds, and the opponent's manoeuvre.

    The defaults are the values ``lili/DrivingSteer-v0`` uses; the module docstring of
    :mod:`lili.envs.driving_steer` explains why.
    """

    n_lanes: int = 3
    lane_width: float = 4.0
    road_length: float = 500.0
    car_length: float = 5.0
    car_width: float = 2.0
    ego_speed: float = 20.0
    opponent_speed: float = 14.0
    gap: float = 15.0
    """Initial distance between the cars' centres along the road (opponent ahead) [m]."""
    switch_time: float = 1.4
    """When the opponent starts its lane change, from the start of the interaction [s]."""
    dt: float = 0.2
    """Control period: one env step [s]."""
    substeps: int = 4
    """Integration steps per control period (simulation frequency = substeps / dt)."""

    @property
    def start_lane(self) -> int:
        """Both cars start in the middle lane."""
        return self.n_lanes // 2

    def lane_center(self, lane: int) -> float:
        """The lateral coordinate y of lane ``lane``'s centre line."""
        return (lane - self.start_lane) * self.lane_width

    @property
    def road_edges(self) -> tuple[float, float]:
        """(left, right) edges of the road in y."""
        half = self.lane_width / 2
        return self.lane_center(0) - half, self.lane_center(self.n_lanes - 1) + half


@dataclass
class CarState:
    """One car after a step. Velocity and yaw rate are the rates over the last integration step."""

    position: np.ndarray = field(default_factory=lambda: np.zeros(2))
    """(x, y) of the car's centre [m]."""
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(2))
    """(vx, vy) [m/s], including the bicycle model's slip."""
    yaw_rate: float = 0.0
    """Heading rate [rad/s], positive turning right."""
    heading: float = 0.0
    """Heading [rad] from the road's direction (needed to draw the car)."""


@dataclass
class SimState:
    """What a backend reports after ``reset`` and ``step``."""

    ego: CarState
    opponent: CarState
    collided: bool = False
    """The two cars' bodies touched during the step."""
    off_road: bool = False
    """A corner of the ego's body crossed an outer road edge during the step."""


@runtime_checkable
class SteerBackend(Protocol):
    """A simulator of the two cars. It owns the opponent's driving; the env owns the rules."""

    def reset(self, scenario: Scenario, target_lane: int) -> SimState:
        """Place both cars per ``scenario``; the opponent will switch into ``target_lane``."""

    def step(self, steer: float) -> SimState:
        """Hold the ego's steering angle ``steer`` [rad] for one control period ``scenario.dt``.

        Stops integrating at the first collision or road-edge crossing and reports it.
        """


class HighwayBackend:
    """Two cars on a straight highway-env road, integrated with highway-env's bicycle model.

    The ego is a :class:`highway_env.vehicle.kinematics.Vehicle` driven by the steering angle at
    constant speed (acceleration 0). The opponent is a
    :class:`highway_env.vehicle.controller.ControlledVehicle` with faster lateral gains than
    highway-env's default (2.6 m sideways within 0.4 s instead of 2.0 m: "aggressive"); it
    holds the middle lane at constant speed until ``scenario.switch_time`` and then targets
    ``target_lane``. Collisions are highway-env's (``Road.step``): the two rectangles overlap, or
    will overlap within one integration step at their current velocities. No rendering, no lane
    bookkeeping and no ``AbstractEnv``: ``highway-v0`` ran at about 1 step/s on the shared
    2-core machine, this at about 1 ms per step.
    """

    def __init__(self) -> None:
        # highway-env pulls in pygame and its own envs; import it only when a backend is built so
        # that the interface above stays importable without it.
        from highway_env.road.lane import StraightLane
        from highway_env.road.road import Road, RoadNetwork
        from highway_env.vehicle.controller import ControlledVehicle
        from highway_env.vehicle.kinematics import Vehicle

        class EgoVehicle(Vehicle):
            def on_state_update(self) -> None:
                # highway-env re-finds the nearest lane after every integration step for its own
                # observations and rewards; nothing here reads it, and it is a third of the cost.
                pass

        class AggressiveVehicle(ControlledVehicle):
            # Lateral time constants shorter than highway-env's 0.2 s and 0.6 s: a sudden swerve.
            TAU_HEADING = 0.15
            TAU_LATERAL = 0.4
            TAU_PURSUIT = 0.5 * TAU_HEADING
            KP_HEADING = 1 / TAU_HEADING
            KP_LATERAL = 1 / TAU_LATERAL

            def on_state_update(self) -> None:
                # Its controller steers by target_lane_index, never by the nearest lane.
                pass

        self._lane_cls, self._road_cls, self._network_cls = StraightLane, Road, RoadNetwork
        self._ego_cls, self._opponent_cls = EgoVehicle, AggressiveVehicle
        self.scenario: Scenario | None = None
        self._road = None
        self._ego = None
        self._opp = None

    def _build_road(self, sc: Scenario):
        network = self._network_cls()
        for lane in range(sc.n_lanes):
            y = sc.lane_center(lane)
            # The road starts behind the ego so that its rear corners are on a lane at x = 0.
            network.add_lane("a", "b", self._lane_cls(
                [-2 * sc.car_length, y], [sc.road_length, y], width=sc.lane_width,
                speed_limit=sc.ego_speed))
        # Nothing here draws from the road's generator; it is seeded only so that nothing could.
        return self._road_cls(network=network, np_random=np.random.RandomState(0),
                              record_history=False)

    def reset(self, scenario: Scenario, target_lane: int) -> SimState:
        if not 0 <= target_lane < scenario.n_lanes:
            raise ValueError(
                f"target_lane={target_lane!r} is invalid; allowed: 0..{scenario.n_lanes - 1}")
        if self._road is None or scenario != self.scenario:
            self._road = self._build_road(scenario)
        self.scenario = scenario
        road = self._road
        sc = scenario
        mid = ("a", "b", sc.start_lane)
        self._ego = self._ego_cls(road, [0.0, 0.0], heading=0.0, speed=sc.ego_speed)
        self._opp = self._opponent_cls(road, [sc.gap, 0.0], heading=0.0,
                                       speed=sc.opponent_speed, target_lane_index=mid,
                                       target_speed=sc.opponent_speed)
        for car in (self._ego, self._opp):
            car.LENGTH, car.WIDTH = sc.car_length, sc.car_width
            car.diagonal = float(np.hypot(sc.car_length, sc.car_width))
        road.vehicles = [self._ego, self._opp]
        self._target = ("a", "b", int(target_lane))
        self._dt = sc.dt / sc.substeps
        # Switch on the integration step that starts at switch_time (rounded, not floored, so
        # that 1.4 / 0.05 = 27.999... still switches at step 28).
        self._switch_step = int(round(sc.switch_time / self._dt))
        self._n = 0
        self._ego.act({"steering": 0.0, "acceleration": 0.0})
        return SimState(self._car_state(self._ego, None, 0.0),
                        self._car_state(self._opp, None, 0.0))

    def step(self, steer: float) -> SimState:
        if self.scenario is None or self._ego is None:
            raise RuntimeError("step() before reset()")
        sc = self.scenario
        ego, opp = self._ego, self._opp
        collided = off_road = False
        before: list[tuple[np.ndarray, float]] = []
        for _ in range(sc.substeps):
            before = [(ego.position.copy(), ego.heading), (opp.position.copy(), opp.heading)]
            if self._n >= self._switch_step:
                opp.target_lane_index = self._target
            ego.act({"steering": float(steer), "acceleration": 0.0})
            opp.act()
            self._road.step(self._dt)
            self._n += 1
            collided = bool(ego.crashed or opp.crashed)
            off_road = self._off_road()
            if collided or off_road:
                break
        states = [self._car_state(car, prev, self._dt)
                  for car, prev in zip((ego, opp), before, strict=True)]
        return SimState(states[0], states[1], collided, off_road)

    def _off_road(self) -> bool:
        sc, ego = self.scenario, self._ego
        left, right = sc.road_edges
        # Half the lateral extent of the rotated body, i.e. of its corners around the centre.
        half = 0.5 * (sc.car_length * abs(np.sin(ego.heading))
                      + sc.car_width * abs(np.cos(ego.heading)))
        y = ego.position[1]
        return bool(y - half < left or y + half > right)

    @staticmethod
    def _car_state(car, prev: tuple[np.ndarray, float] | None, dt: float) -> CarState:
        if prev is None:
            velocity = car.speed * np.array([np.cos(car.heading), np.sin(car.heading)])
            yaw_rate = 0.0
        else:
            velocity = (car.position - prev[0]) / dt
            yaw_rate = (car.heading - prev[1]) / dt
        return CarState(car.position.copy(), np.asarray(velocity, dtype=np.float64),
                        float(yaw_rate), float(car.heading))
