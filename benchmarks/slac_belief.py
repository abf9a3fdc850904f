"""What SLAC's belief knows of the state, as its critic reads it, on the agent's own play.

    python benchmarks/slac_belief.py RUN_GLOB [RUN_GLOB ...] [--window 200] [--last 5]
        [--name slac_belief]

SLAC's critic reads a sample z_t = (z1_t, z2_t) of its latent filter run over the K + 1
frames that end at t + 1 (:meth:`lili.agents.slac.SLACCore._batch`), never the observation
itself. For every run folder of a SLAC-family agent with a checkpoint (``lili train`` keeps
them; committed records do not), this takes the last ``--window`` interactions of the
checkpoint's replay buffer (the agent's own play, as it trains on it), builds for every step
the critic's latent exactly as training does (same windows, a posterior sample; key fixed
here), and asks three things of it, per observation dimension (the network frame: the
normalised observation):

- **decoder R^2**: how much of the frame's variance the model's own decoder
  p(x_t | z_t) explains (its mean against the frame);
- **linear R^2**: a least-squares probe z_t -> x_t fitted on the first 70% of the window's
  interactions, scored on the rest (how much a linear read of the critic's input recovers);
- the same two over ``--last`` steps before an interaction that ended by contact (landing or
  crash, shorter than the horizon), where a critic must tell a soft touchdown from a crash.

And of the reward model p(r_t | z_t, a_t, z_t+1): R^2 of its mean against the normalised
reward over the steps before the last and over the last steps (Lunar Lander's terminal reward
replaces the step's). R^2 = 1 - SSE / SST over the transitions scored; 1 is a perfect read, 0
no better than the mean. Prints the tables and writes ``benchmarks/results/<--name>.json``.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from _results import records_args, write_result

from lili.agents.slac import LatentModel, SLACCore, gather_sequences
from lili.runs import load_checkpoint, load_trained
from lili.train import Stream

OBS_NAMES = {8: ("x", "y", "vx", "vy", "angle", "ang. vel.", "left leg", "right leg")}
"""Names of the observation's dimensions where the env's are known (Lunar Lander's eight)."""


def r2(pred: np.ndarray, true: np.ndarray) -> np.ndarray:
    """Per-column R^2 = 1 - SSE / SST (NaN where the column does not vary or is empty)."""
    if len(true) == 0:
        return np.full(true.shape[1:], np.nan)
    sst = ((true - true.mean(0)) ** 2).sum(0)
    sse = ((true - pred) ** 2).sum(0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(sst > 0, 1 - sse / sst, np.nan)


def linear_probe(z_fit: np.ndarray, x_fit: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Least-squares prediction of x from z (with an intercept), fitted on the fit part."""
    a = np.hstack([z_fit, np.ones((len(z_fit), 1))])
    w, *_ = np.linalg.lstsq(a, x_fit, rcond=None)
    return np.hstack([z, np.ones((len(z), 1))]) @ w


def critic_latents(core: SLACCore, state, arrays: dict[str, jax.Array], slots: np.ndarray,
                   seed: int = 0) -> dict[str, np.ndarray]:
    """For every valid step of the interactions in buffer ``slots``: the critic's latent z_t,
    the network frame x_t, the decoder's mean at z_t, the reward model's mean (from z_t, a_t
    and z_t+1) and the normalised reward; plus each step's interaction (its position in
    ``slots``), t and the interaction's length."""
    length = np.asarray(arrays["length"])[slots]
    rows = [(i, s, t) for i, s in enumerate(slots) for t in range(int(length[i]))]
    which, slot, t = (np.array(v) for v in zip(*rows, strict=True))
    seq = gather_sequences(arrays, jnp.asarray(slot), jnp.asarray(t), core.seq_len)
    norm, params = state.norm, state.aux["slac"]

    @jax.jit
    def run(seq, key):
        x = core._frames_x(norm, seq["win_obs"], seq["win_t"], seq["win_valid"])
        z1, z2, _, _ = core.posterior(params, x, seq["win_act"], key, core.critic_samples)
        pos = seq["pos"][:, None, None]
        take = lambda v, p: jnp.take_along_axis(v, p, 1)[:, 0]  # noqa: E731
        z1t, z2t, z1n, z2n = take(z1, pos), take(z2, pos), take(z1, pos + 1), take(z2, pos + 1)
        x_t = take(x, pos)
        decoded = core.lvm.apply(params, z1t, z2t, method=LatentModel.decode)
        a_t = take(seq["win_act"], pos)
        r_hat, _ = core.lvm.apply(params, z1t, z2t, a_t, z1n, z2n,
                                  method=LatentModel.reward_dist)
        r_t = norm.rew(take(seq["win_rew"], pos[..., 0]))
        return jnp.concatenate([z1t, z2t], -1), x_t, decoded, r_hat, r_t

    z, x, decoded, r_hat, r = (np.asarray(v) for v in run(seq, jax.random.PRNGKey(seed)))
    return {"z": z, "x": x, "decoded": decoded, "r_hat": r_hat, "r": r, "which": which,
            "t": t, "length": length[which]}


def belief_scores(d: dict[str, np.ndarray], n_interactions: int, horizon: int, last: int,
                  obs_dim: int) -> dict[str, object]:
    """The R^2s of the module docstring from :func:`critic_latents`'s arrays."""
    fit = d["which"] < int(0.7 * n_interactions)
    near = (d["length"] < horizon) & (d["t"] >= d["length"] - last)
    probe = linear_probe(d["z"][fit], d["x"][fit], d["z"])
    test = ~fit
    final = d["t"] == d["length"] - 1

    def dims(v: np.ndarray) -> list[float | None]:
        return [None if np.isnan(u) else round(float(u), 4) for u in v[:obs_dim]]

    return {
        "steps": int(len(d["t"])), "near_steps": int(near.sum()),
        "decoder_r2": dims(r2(d["decoded"], d["x"])),
        "decoder_rms": dims(np.sqrt(((d["decoded"] - d["x"]) ** 2).mean(0))),
        "linear_r2": dims(r2(probe[test], d["x"][test])),
        "decoder_r2_near": dims(r2(d["decoded"][near], d["x"][near])),
        "linear_r2_near": dims(r2(probe[test & near], d["x"][test & near])),
        "reward_r2_steps": round(float(r2(d["r_hat"][~final, None],
                                          d["r"][~final, None])[0]), 4),
        "reward_r2_last": round(float(r2(d["r_hat"][final, None], d["r"][final, None])[0]), 4),
    }


def _cells(v: list[float | None]) -> str:
    return " | ".join("-" if u is None else f"{u:.2f}" for u in v)


def main() -> None:
    p, args, folders = records_args(__doc__, "slac_belief", {"window": 200, "last": 5})
    loaded = []
    for folder in folders:  # every run checked before any is probed
        try:
            agent, env, cfg, at = load_trained(folder)
            stream = Stream.for_agent(agent, env)  # the replay buffer the checkpoint holds
            env.close()
            load_checkpoint(folder, agent, stream)
        except ValueError as e:
            p.error(f"run {folder}: {e}; allowed: a run folder of lili train with its checkpoints")
        if not isinstance(agent.core, SLACCore):
            p.error(f"run {folder} is a {cfg['algo']!r} run; allowed: SLAC or a SLAC variant")
        if stream.count < args.window:
            p.error(f"run {folder} holds {stream.count} interactions; allowed: --window "
                    f"at most that")
        loaded.append((folder, agent, cfg, at, stream.buffer))
    out = []
    for folder, agent, cfg, at, buf in loaded:
        n = buf.count
        slots = np.arange(n - args.window, n)
        d = critic_latents(agent.core, agent.state, buf.arrays, slots % buf.capacity)
        row = {"run": folder, "algo": cfg["algo"], "seed": cfg["seed"], "checkpoint": at,
               "decoder_std": agent.core.options.decoder_std,
               "interactions": [int(slots[0]), int(slots[-1])],
               **belief_scores(d, args.window, buf.horizon, args.last, buf.obs_dim)}
        out.append(row)
    obs_dim = len(out[0]["decoder_r2"])
    names = OBS_NAMES.get(obs_dim, tuple(f"x{i}" for i in range(obs_dim)))
    head = "| run | checkpoint | read | steps | " + " | ".join(names) + " |"
    rule = "|---|---:|---|---:|" + "---:|" * obs_dim
    lines = []
    for r in out:
        for read, key, steps in (("decoder", "decoder_r2", "steps"),
                                 ("linear", "linear_r2", "steps"),
                                 (f"decoder rms error (std {r['decoder_std']:.2f})", "decoder_rms",
                                  "steps"),
                                 (f"decoder, last {args.last}", "decoder_r2_near", "near_steps"),
                                 (f"linear, last {args.last}", "linear_r2_near", "near_steps")):
            lines.append(f"| {r['run']} | {r['checkpoint']} | {read} | {r[steps]} | "
                         f"{_cells(r[key])} |")
    rew = [f"| {r['run']} | {r['checkpoint']} | {r['reward_r2_steps']:.2f} | "
           f"{r['reward_r2_last']:.2f} |" for r in out]
    table = "\n".join([
        f"R^2 of the normalised observation read from the critic's latent over each run's last "
        f"{args.window} interactions (its own play): by the model's decoder, by a linear probe "
        f"(fitted on the first 70%, scored on the rest); 'rms error': the decoder's root mean "
        f"square error in the frame's units, beside its fixed std; 'last {args.last}': the steps "
        f"before an interaction that ended by contact", "", head, rule, *lines, "",
        "R^2 of the reward model's mean against the normalised reward", "",
        "| run | checkpoint | steps before the last | last steps |", "|---|---:|---:|---:|",
        *rew])
    write_result(args.name, table, runs=out, window=args.window, last=args.last)


if __name__ == "__main__":
    main()
