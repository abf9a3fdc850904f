"""``lili/InfluenceFlee-v0``: rules, registration, the contract, the scripted policies' derived
returns, and that the last interaction tells the next strategy."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import lili.envs  # noqa: F401
from lili import cli
from lili.envs import resolve_env_id
from lili.envs.checker import check_env
from lili.envs.influence import HELD, SUITE, InfluenceFleeEnv, make_scripted, play
from lili.envs.influence.flee import HOME, SLOT, SLOTS, end_slot, fled
from lili.envs.influence.line import move_to

ENV_ID = "lili/InfluenceFlee-v0"


def test_registered_and_passes_the_checkers(capsys) -> None:
    assert resolve_env_id("influence-flee") == ENV_ID
    check_env(gym.make(ENV_ID))
    # Through the command's own code, in this process (tests/test_influence_envs.py runs it
    # from the shell for the suite's other envs; a fresh process here only adds JAX's import).
    assert cli.main(["check-env", "influence-flee"]) == 0
    assert "passes" in capsys.readouterr().out


def _end_at(env: InfluenceFleeEnv, x_end: float) -> dict:
    """Play one interaction that runs to ``x_end`` and stays; return the last step's info."""
    obs, _ = env.reset()
    while True:
        obs, _, term, trunc, info = env.step(move_to(float(obs[0]), x_end, SLOT))
        if term or trunc:
            return info


@pytest.mark.parametrize("k, x_end, nxt", [
    (1, 0.25, 2), (1, 0.37, 2), (1, 0.375, 0), (1, 0.5, 0), (1, 1.0, 0), (1, -0.5, 2),
    (2, 0.5, 3), (2, 0.75, 1), (2, 0.0, 3), (3, 1.0, 2), (3, 0.75, 4),
    (4, 1.0, -1), (4, 0.0, -1), (-4, -1.0, 1), (-4, 0.5, 1),
    (-1, -0.25, -2), (-1, -0.5, 0), (-1, 0.25, -2), (-3, -0.9, -2), (-2, -0.62, -3),
    (0, 0.0, 0), (0, 0.12, 0), (0, -0.125, 0), (0, 0.125, -1), (0, 0.6, -1), (0, -0.13, 1),
])
def test_rules(k: int, x_end: float, nxt: int) -> None:
    env = InfluenceFleeEnv()
    env.reset(seed=0)
    env.partner.k = k
    info = _end_at(env, x_end)
    assert info["outcome"] == end_slot(x_end)
    assert env.partner.k == nxt == fled(k, end_slot(x_end))
    assert env.partner.strategy_id() == nxt + SLOTS
    assert env.partner.strategy()[0] == pytest.approx(SLOT * nxt)


def test_rewards_are_the_distance_to_the_partner() -> None:
    env = InfluenceFleeEnv()
    env.reset(seed=0)
    env.partner.k = -3  # g = -0.75
    obs, info = env.reset()
    assert obs.tolist() == [0.0] and info["strategy"][0] == pytest.approx(-0.75)
    rewards = [env.step(np.array([a], np.float32))[1] for a in (-1.0, -1.0, 0.5, 2.0)]
    assert rewards == pytest.approx([-0.5, -0.25, -0.375, -0.625])  # x = -.25, -.5, -.375, -.125


def test_the_first_slot_is_never_home_and_reset_seed_replays() -> None:
    firsts = [InfluenceFleeEnv().reset(seed=s)[1]["strategy_id"] for s in range(300)]
    assert set(firsts) == set(range(2 * SLOTS + 1)) - {HOME}
    assert max(np.bincount(firsts)) < 60  # about uniform: 300 / 8 = 37.5 each
    policy = lambda o, i: np.array([0.6], np.float32)  # noqa: E731
    a, b = (play(InfluenceFleeEnv(), policy, 20, seed=7) for _ in range(2))
    assert a.returns.tolist() == b.returns.tolist()
    assert a.strategy_ids.tolist() == b.strategy_ids.tolist()


def test_scripted_policies_meet_their_derived_returns() -> None:
    known = SUITE[ENV_ID][1]
    assert known == pytest.approx({"no-information": -2.2083333, "greedy": -0.625,
                                   "influencer": 0.0})
    for seed in (0, 1, 2):
        rollouts = {name: play(gym.make(ENV_ID), make_scripted(ENV_ID, name, seed), 80, seed)
                    .last(48) for name in known}  # 48: whole 6- and 8-interaction cycles
        for name, r in rollouts.items():
            assert r.mean_return() == pytest.approx(known[name], abs=1e-5), (name, seed)
        # The behavioural evidence: only the influencer holds the partner home; greedy and
        # no information cycle through 8 and 6 slots.
        assert np.all(rollouts["influencer"].strategy_ids == HELD[ENV_ID][0])
        assert set(rollouts["greedy"].strategy_ids.tolist()) == set(range(9)) - {HOME}
        assert set(rollouts["no-information"].strategy_ids.tolist()) == {0, 1, 2, 3, 4, 5}
    assert known["influencer"] >= known["greedy"] + 0.45
    assert known["greedy"] >= known["no-information"] + 1.0


def test_no_fixed_trajectory_beats_the_derived_no_information_bound() -> None:
    """An exhaustive search over fixed trajectories on a 1/8 grid (each step at most one slot)
    finds none better than the docstring's supremum, -25/12, from any first slot."""
    steps = np.arange(-2, 3) / 8

    def long_run(xs: tuple[float, ...], k: int) -> float:
        k_end, seen, order = end_slot(xs[-1]), {}, []
        while k not in seen:
            seen[k] = len(order)
            order.append(k)
            k = fled(k, k_end)
        return float(np.mean([sum(abs(x - SLOT * c) for x in xs) for c in order[seen[k]:]]))

    best, frontier = -np.inf, [()]
    for _ in range(4):
        frontier = [(*xs, x) for xs in frontier for x in (xs[-1] if xs else 0.0) + steps]
    for xs in frontier:
        worst = min(-long_run(xs, k) for k in range(-SLOTS, SLOTS + 1) if k)
        best = max(best, worst)
    assert best == pytest.approx(-25 / 12)


def test_the_last_interaction_tells_the_next_slot() -> None:
    """From one interaction's observations and rewards alone (what LILI's encoder reads), the
    slot (the candidate that explains the rewards) and where the ego stopped give the next
    slot, every time the ego moved."""
    env = InfluenceFleeEnv()
    rng = np.random.default_rng(0)
    obs, info = env.reset(seed=5)
    candidates = SLOT * np.arange(-SLOTS, SLOTS + 1)
    kinds = set()
    for _ in range(200):
        xs, rewards, true_k = [], [], info["strategy_id"] - SLOTS
        drift = rng.uniform(-1, 1)
        while True:
            obs, r, term, trunc, info = env.step(
                np.clip([drift + rng.uniform(-0.6, 0.6)], -1, 1).astype(np.float32))
            xs.append(float(obs[0]))
            rewards.append(r)
            if term or trunc:
                break
        misfit = [np.abs(np.abs(np.array(xs) - g) + np.array(rewards)).max()
                  for g in candidates]
        k = int(np.argmin(misfit)) - SLOTS
        assert k == true_k
        obs, info = env.reset()
        assert fled(k, end_slot(xs[-1])) + SLOTS == info["strategy_id"]
        kinds.add((k == 0, k == fled(k, end_slot(xs[-1]))))
    # It saw the partner home and away, staying and moving.
    assert kinds >= {(True, True), (False, False)}, kinds


def test_render() -> None:
    env = gym.make(ENV_ID, render_mode="rgb_array")
    env.reset(seed=0)
    a = env.render()
    env.step(np.array([1.0], np.float32))
    assert a.shape == (40, 200, 3) and (a != env.render()).any()


@pytest.mark.parametrize("kwargs, match", [
    ({"horizon": 3}, r"horizon=3 is invalid; allowed: an integer >= 4"),
    ({"horizon": 4.0}, r"horizon=4.0 is invalid"),
    ({"horizon": True}, r"horizon=True is invalid"),
    ({"render_mode": "human"}, "render_mode='human'"),
])
def test_bad_kwargs(kwargs, match) -> None:
    with pytest.raises(ValueError, match=match):
        InfluenceFleeEnv(**kwargs)
    if "horizon" in kwargs:  # through gym.make too, as `lili train --env-kwarg` passes them
        with pytest.raises(ValueError, match=match):
            gym.make(ENV_ID, **kwargs)


def test_unknown_kwarg_is_one_clear_error() -> None:
    from lili.envs.spec import make_env

    with pytest.raises(ValueError, match=r"unknown env kwarg\(s\) 'returns' for "
                                         r"influence-flee; allowed: horizon$"):
        make_env("influence-flee", {"returns": 0.1})
