"""Drift diagnostic: why does an agent told the last interaction not learn to influence?

    python benchmarks/drift_lagged.py [--interactions 2000] [--seeds 3] [--out DIR]

In ``lili/InfluenceDrift-v0`` LILI and the Oracle (last interaction) (``--algo oracle-last``:
SAC told the partner's goal in the last interaction and that interaction's last observation
and action) both stay at the no-information level, while the Oracle, told the current goal,
learns to hold it next to the start (``docs/journal/2026-11-to-12.md``, "Drift with a returning
partner"). The partner reacts to the *sign* of where the ego ended, so for the lagged agent
the next interaction's value steps at x_end = 0, inside a continuous input. This script
trains SAC (the default agent config, as the ``influence`` preset, or ``--set`` fields) on
lagged observations that carry the same information about the partner's next goal:

- ``position``: :class:`lili.envs.wrappers.LastInteractionObservation` (the Oracle (last
  interaction) itself);
- ``side``: the last interaction's goal and the side of 0 where it ended (+1 / -1, 0 before
  the first interaction), so the step is a jump of a discrete input, as for the Oracle;
- ``predicted``: the goal that the last interaction predicts (its goal moved one grid step
  toward the side where it ended; 0 before the first interaction): the Oracle's
  observation, wrong only after a return of the partner, which nothing in the last
  interaction shows (:func:`lili.envs.influence.drift.from_last_interaction` plays the
  scripted policies on the same prediction);
- ``predicted-onehot``: the same prediction as one of eight indicators, the goals told
  apart but not in order (a test of whether order is what ``predicted`` has over the rest);
- ``predicted-embedding``: the same prediction as a fixed random vector per goal, dense
  and overlapping like a learned latent but fixed for every goal, produced yet or not (a
  test of whether what the indicators have over a learned latent is that fixedness or
  their orthogonality);
- ``predicted-embedding-noisy``: that vector plus Gaussian noise drawn once per interaction,
  spread within a goal about as much as LILI's latents under exploration noise;
- ``noisy-in-critic`` / ``noisy-in-actor``: both codes side by side, the noisy one read by
  the critic only (the actor reads the clean one) or by the actor only, which tells whether
  the noise stops SAC through the values it learns or through the actions it takes;
  ``noisy-in-q`` / ``noisy-in-target``: the noisy one read by the critic's Q input only or by
  its bootstrap target only (the next state's critic input);
- ``latent`` (with ``--latent-of RUN``): the latent that a trained LILI's encoder, frozen,
  computes from the last interaction, so that the latent's code is tested without the
  co-adaptation of encoder and policy.

If ``side`` learns to influence and ``position`` does not, the blurred step is the obstacle;
if ``predicted`` learns to influence as the Oracle does and ``side`` does not, computing the
drift from the lagged input is; if ``predicted`` fails too, the returns the last interaction
cannot foresee are; if ``latent`` fails where ``predicted`` learns, LILI's latent is as hard
to act on as the raw last interaction, moving or not.
Each seed scores the mean return over its last 10% (mean +- s.e. over seeds) and the share of
those interactions with g = +-0.125 ("held"). Per-seed records (metrics.csv, summary.json)
go under ``--out``/<variant>/seed_<k>; the table to ``benchmarks/results/<--name>.{md,json}``.
"""

from __future__ import annotations

import argparse
import csv
import json
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any, ClassVar

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
from _results import RESULTS, check_result_name
from gymnasium import spaces

import lili.envs  # noqa: F401 - registers the envs
from lili.agents import SAC, check_config, load_agent
from lili.agents.sac import SACCore
from lili.buffer import InteractionBuffer
from lili.cli import UsageError, parse_overrides
from lili.config import AgentConfig
from lili.dists import tanh_gaussian
from lili.envs.influence import HELD
from lili.envs.influence.drift import GOALS, drifted
from lili.envs.wrappers import LastInteractionObservation
from lili.play.policy import agent_file_for_run
from lili.report.stats import mean_se
from lili.runs import final_window

ROOT = Path(__file__).resolve().parent.parent
ENV = "lili/InfluenceDrift-v0"


class LastSideObservation(gym.Wrapper):
    """Append the last interaction's goal and the side of 0 where it ended (Drift's x is the
    only observation); zeros before the first interaction of a sequence."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.observation_space = spaces.Box(np.array([-1, -1, -1], np.float32),
                                            np.array([1, 1, 1], np.float32), dtype=np.float32)
        self._last = np.zeros(2, np.float32)
        self._goal, self._end, self._started = 0.0, 0.0, False

    def reset(self, **kwargs: Any):
        obs, info = self.env.reset(**kwargs)
        if kwargs.get("seed") is not None or not self._started:
            self._last = np.zeros(2, np.float32)
        else:
            self._last = np.array([self._goal, 1.0 if self._end >= 0 else -1.0], np.float32)
        self._started = True
        self._goal, self._end = float(info["strategy"][0]), float(obs[0])
        return self._obs(obs), info

    def step(self, action: Any):
        obs, reward, terminated, truncated, info = self.env.step(action)
        self._end = float(obs[0])
        return self._obs(obs), reward, terminated, truncated, info

    def _obs(self, obs: np.ndarray) -> np.ndarray:
        return np.concatenate([np.asarray(obs, np.float32), self._last])


class PredictedGoalObservation(LastSideObservation):
    """Append the goal that the last interaction predicts (0 before the first): the last goal
    moved one grid step toward the side where the ego ended, as the partner moves unless it
    returns near the start."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.observation_space = spaces.Box(np.array([-1, -1], np.float32),
                                            np.array([1, 1], np.float32), dtype=np.float32)

    def _predicted(self) -> int | None:
        """The predicted goal's index on :data:`GOALS`, None before the first interaction."""
        goal, side = self._last
        return None if side == 0 else drifted(int(np.argmin(np.abs(GOALS - goal))), int(side))

    def _obs(self, obs: np.ndarray) -> np.ndarray:
        index = self._predicted()
        return np.array([obs[0], 0.0 if index is None else GOALS[index]], np.float32)


class PredictedOneHotObservation(PredictedGoalObservation):
    """The same prediction as one of eight indicators (all 0 before the first interaction):
    the goals told apart but not laid out in order, as a latent might carry them."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        n = 1 + len(GOALS)
        self.observation_space = spaces.Box(-np.ones(n, np.float32), np.ones(n, np.float32),
                                            dtype=np.float32)

    def _obs(self, obs: np.ndarray) -> np.ndarray:
        out = np.zeros(1 + len(GOALS), np.float32)
        out[0] = obs[0]
        index = self._predicted()
        if index is not None:
            out[1 + index] = 1.0
        return out


EMBEDDING = (np.random.default_rng(0).normal(size=(len(GOALS), len(GOALS)))
             / np.sqrt(len(GOALS))).astype(np.float32)
"""The ``predicted-embedding`` variant's fixed vector per goal (row = goal index)."""


class PredictedEmbeddingObservation(PredictedOneHotObservation):
    """The same prediction as a fixed random vector per goal (:data:`EMBEDDING`; zeros before
    the first interaction): named as fixedly as by the indicators, every goal the agent has
    not produced yet included, but dense and overlapping like a learned latent."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        n = 1 + len(GOALS)
        self.observation_space = spaces.Box(np.full(n, -np.inf, np.float32),
                                            np.full(n, np.inf, np.float32), dtype=np.float32)

    def _obs(self, obs: np.ndarray) -> np.ndarray:
        hot = super()._obs(obs)
        return np.concatenate([hot[:1], hot[1:] @ EMBEDDING])


EMBEDDING_NOISE = 0.18
"""Per-dimension std of ``predicted-embedding-noisy``'s noise: an RMS spread of 0.51, 0.66 of
the median distance between neighbouring rows of :data:`EMBEDDING` (0.77), as LILI's latents
spread within one predicted goal under exploration noise (0.42-1.29 of that distance)."""


class NoisyEmbeddingObservation(PredictedEmbeddingObservation):
    """:class:`PredictedEmbeddingObservation` plus Gaussian noise drawn once per interaction
    (a latent is held for a whole interaction) from a generator seeded at ``reset(seed=...)``:
    a fixed code that moves within a goal as a learned latent does."""

    def __init__(self, env: gym.Env, noise: float = EMBEDDING_NOISE) -> None:
        super().__init__(env)
        self.noise = noise
        self._rng, self._noise = np.random.default_rng(0), np.zeros(len(GOALS), np.float32)

    def reset(self, **kwargs: Any):
        if kwargs.get("seed") is not None:
            self._rng = np.random.default_rng(kwargs["seed"])
        self._noise = (self._rng.normal(size=len(GOALS)) * self.noise).astype(np.float32)
        return super().reset(**kwargs)

    def _obs(self, obs: np.ndarray) -> np.ndarray:
        out = super()._obs(obs)
        if self._predicted() is not None:
            out[1:] += self._noise
        return out


class SplitNoisyEmbeddingObservation(NoisyEmbeddingObservation):
    """Both codes side by side: x, the fixed code of the predicted goal, then that code plus
    the interaction's noise. The ``noisy-in-*`` variants (:class:`_SplitCore`) show each
    network one of the two, so that the noise reaches only the critic or only the actor."""

    def __init__(self, env: gym.Env, noise: float = EMBEDDING_NOISE) -> None:
        super().__init__(env, noise)
        n = 1 + 2 * len(GOALS)
        self.observation_space = spaces.Box(np.full(n, -np.inf, np.float32),
                                            np.full(n, np.inf, np.float32), dtype=np.float32)

    def _obs(self, obs: np.ndarray) -> np.ndarray:
        clean = PredictedEmbeddingObservation._obs(self, obs)
        noisy = NoisyEmbeddingObservation._obs(self, obs)
        return np.concatenate([clean, noisy[1:]])


class _SplitCore(SACCore):
    """SAC whose networks read different codes of :class:`SplitNoisyEmbeddingObservation`.

    ``noisy_in`` says which input reads the noisy code (every other reads the clean one):
    ``critic`` (the Q input and the bootstrap target's), ``q`` (the Q input only), ``target``
    (the bootstrap target's critic input only) or ``actor`` (the actor, wherever it acts)."""

    noisy_in: ClassVar[str] = "critic"

    def _view(self, x: jax.Array, noisy: bool) -> jax.Array:
        n = len(GOALS)
        code = x[..., 1 + n:1 + 2 * n] if noisy else x[..., 1:1 + n]
        return jnp.concatenate([x[..., :1], code, x[..., 1 + 2 * n:]], -1)

    def _views(self, x: jax.Array, target: bool) -> tuple[jax.Array, jax.Array]:
        """(critic input, actor input) from the full input, at the target side or not."""
        critic_noisy = self.noisy_in in ("critic", "target" if target else "q")
        return self._view(x, critic_noisy), self._view(x, self.noisy_in == "actor")

    def _input_dims(self) -> tuple[int, int]:
        return self.x_dim - len(GOALS), self.x_dim - len(GOALS)

    def _target_inputs(self, state, batch):
        return self._views(super()._target_inputs(state, batch)[0], target=True)

    def _inputs(self, model, state, batch):
        x, _, z = super()._inputs(model, state, batch)
        return (*self._views(x, target=False), z)

    def _act(self, actor, norm, obs, acting, key, deterministic):
        x = jnp.concatenate([self._x(norm, obs, acting.t), acting.z], -1)
        mean, log_std = self.actor.apply(actor, self._views(x, target=False)[1])
        a = jnp.tanh(mean) if deterministic else tanh_gaussian(mean, log_std, key)[0]
        return a, acting.replace(t=acting.t + 1)


def _split_sac(noisy_in: str) -> type[SAC]:
    """SAC on :class:`SplitNoisyEmbeddingObservation` with the noisy code in ``noisy_in``."""
    core = type(f"_Noisy_{noisy_in}_Core", (_SplitCore,), {"noisy_in": noisy_in})
    return type(f"Noisy_{noisy_in}_SAC", (SAC,), {"core_cls": core})


SPLITS = ("critic", "q", "target", "actor")
"""Where the ``noisy-in-*`` variants put the noisy code (see :class:`_SplitCore`)."""


class FrozenLatentObservation(gym.Wrapper):
    """Append the latent that a trained LILI's encoder, frozen, computes from the last
    interaction (its ``initial_state()`` latent before the first): LILI's own latent as an
    input that no longer moves, so SAC on it separates what the latent's code allows from
    the co-adaptation of encoder and policy in LILI."""

    def __init__(self, env: gym.Env, agent: Any) -> None:
        super().__init__(env)
        self.agent = agent
        self._new_sequence()
        low = np.concatenate([env.observation_space.low, np.full(self._z.shape, -np.inf)])
        self.observation_space = spaces.Box(low.astype(np.float32), -low.astype(np.float32),
                                            dtype=np.float32)

    def _new_sequence(self) -> None:
        a = self.agent
        self._buffer = InteractionBuffer(max(2, a.history + 1), a.horizon, a.obs_dim, a.act_dim)
        self._z, self._traj = np.asarray(a.initial_state().z, np.float32), None

    def reset(self, **kwargs: Any):
        obs, info = self.env.reset(**kwargs)
        if kwargs.get("seed") is not None:
            self._new_sequence()
        elif self._traj is not None:
            self._buffer.add({k: np.asarray(v, np.float32) for k, v in self._traj.items()}, obs)
            self._z = np.asarray(self.agent.next_state(self._buffer).z, np.float32)
        self._traj = {"obs": [], "act": [], "rew": [], "next_obs": []}
        self._obs = obs
        return self._with_z(obs), info

    def step(self, action: Any):
        obs, reward, terminated, truncated, info = self.env.step(action)
        for key, value in (("obs", self._obs), ("act", np.clip(action, -1, 1)), ("rew", reward),
                           ("next_obs", obs)):
            self._traj[key].append(value)
        self._obs = obs
        return self._with_z(obs), reward, terminated, truncated, info

    def _with_z(self, obs: np.ndarray) -> np.ndarray:
        return np.concatenate([np.asarray(obs, np.float32), self._z])


def frozen_latent(run: str) -> Callable[[gym.Env], gym.Env]:
    """The ``latent`` variant's wrapper factory for the LILI run folder ``run``."""
    path, cfg = agent_file_for_run(run)
    if cfg.get("algo") not in ("lili", "lili-no-influence") or cfg.get("env") != ENV:
        raise ValueError(f"--latent-of {run!r} is a {cfg.get('algo')} run on {cfg.get('env')}; "
                         f"allowed: a lili or lili-no-influence run on {ENV}")
    agent = load_agent(path, gym.make(ENV, **cfg.get("env_kwargs", {})))
    return lambda env: FrozenLatentObservation(env, agent)


VARIANTS: dict[str, Callable[[gym.Env], gym.Env]] = {
    "position": LastInteractionObservation, "side": LastSideObservation,
    "predicted": PredictedGoalObservation, "predicted-onehot": PredictedOneHotObservation,
    "predicted-embedding": PredictedEmbeddingObservation,
    "predicted-embedding-noisy": NoisyEmbeddingObservation,
    **{f"noisy-in-{where}": SplitNoisyEmbeddingObservation for where in SPLITS}}
AGENTS: dict[str, type[SAC]] = {f"noisy-in-{where}": _split_sac(where) for where in SPLITS}
"""Variants trained by another agent than plain SAC."""
NOISY = ("predicted-embedding-noisy", *(f"noisy-in-{where}" for where in SPLITS))
LATENT = "latent"  # the variant built from --latent-of (frozen_latent)


def run(variant: str, wrap: Callable[[gym.Env], gym.Env], seed: int, n: int, out: Path,
        config: dict[str, Any] | None = None) -> dict[str, Any]:
    """Train one seed of ``variant`` (SAC on ``wrap``'s observation, with the agent-config
    fields ``config`` changed); write its records; return its score."""
    env = wrap(gym.make(ENV))
    rows: list[dict[str, Any]] = []
    t0 = time.process_time()
    AGENTS.get(variant, SAC)(env, config=config or {}, seed=seed).learn(n, callback=rows.append)
    cpu = time.process_time() - t0
    last = rows[-final_window(n):]
    final = float(np.mean([r["return"] for r in last]))
    held = float(np.mean([r["strategy_id"] in HELD[ENV] for r in last]))
    folder = out / variant / f"seed_{seed}"
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / "metrics.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["interaction", "return", "strategy_id"])
        w.writerows([r["interaction"], f"{r['return']:.6g}", r["strategy_id"]] for r in rows)
    summary = {"env": ENV, "variant": variant, "seed": seed, "interactions": n,
               "config": config or {},
               "final_return": final, "held": held, "cpu_time_s": round(cpu, 1)}
    (folder / "summary.json").write_text(json.dumps(summary, indent=1))
    return summary


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--interactions", type=int, default=2000)
    p.add_argument("--seeds", type=int, default=3)
    p.add_argument("--variants", nargs="+", default=["position", "side", "predicted"],
                   choices=[*VARIANTS, LATENT])
    p.add_argument("--latent-of", metavar="RUN",
                   help="LILI run folder (with a checkpoint) whose frozen encoder the 'latent' "
                        "variant reads")
    p.add_argument("--seed-from", type=int, default=0, help="first seed (default 0)")
    p.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE",
                   help="agent-config field to change in every run (repeatable)")
    p.add_argument("--embedding-noise", type=float, default=EMBEDDING_NOISE,
                   help=f"per-dimension std of the noise of the noisy variants (default "
                   f"{EMBEDDING_NOISE})")
    p.add_argument("--name", default="drift_lagged", help="results file stem")
    p.add_argument("--out", default=str(ROOT / "runs" / "drift_lagged"))
    args = p.parse_args()
    check_result_name(p, args.name)
    try:
        config = parse_overrides(args.set)
        check_config("sac", AgentConfig.from_dict(config))  # every variant here is SAC
    except (UsageError, ValueError) as e:
        p.error(str(e))
    if args.interactions < 100:
        p.error(f"--interactions {args.interactions} is invalid; allowed: an integer >= 100")
    if args.seeds < 1:
        p.error(f"--seeds {args.seeds} is invalid; allowed: an integer >= 1")
    out = Path(args.out)
    seeds = range(args.seed_from, args.seed_from + args.seeds)
    if not 0 <= args.embedding_noise < float("inf"):
        p.error(f"--embedding-noise {args.embedding_noise} is invalid; allowed: a finite "
                "number >= 0")
    wrappers = dict(VARIANTS)
    for v in NOISY:
        wrappers[v] = partial(VARIANTS[v], noise=args.embedding_noise)
    if LATENT in args.variants:
        if not args.latent_of:
            p.error("--variants latent needs --latent-of RUN (a LILI run folder on " + ENV + ")")
        try:
            wrappers[LATENT] = frozen_latent(args.latent_of)
        except (OSError, ValueError) as e:
            p.error(str(e))
    results = {v: [run(v, wrappers[v], s, args.interactions, out, config) for s in seeds]
               for v in args.variants}
    lines = ["| lagged observation | final return | held | per seed | CPU-s per run |",
             "|---|---:|---:|---|---:|"]
    for v, seeds in results.items():
        mean, se = mean_se([r["final_return"] for r in seeds])
        per = " / ".join(f"{r['final_return']:.3f}" for r in seeds)
        held = np.mean([r["held"] for r in seeds])
        cpu = np.mean([r["cpu_time_s"] for r in seeds])
        lines.append(f"| {v} | {mean:.3f} ± {se:.3f} | {100 * held:.0f}% | {per} | {cpu:.0f} |")
    print("\n".join(lines))
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / f"{args.name}.md").write_text("\n".join(lines) + "\n")
    (RESULTS / f"{args.name}.json").write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
