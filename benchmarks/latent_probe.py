"""What a trained agent's latent knows of its partner: probes z^i -> strategy on the
influence suite (issue 14's diagnosis of why LILI stops at the greedy response in Drift).

    python benchmarks/latent_probe.py RUN [RUN ...] [--interactions 1500]

Each run's newest checkpoint plays ``--interactions`` interactions of its own env (the run's
env kwargs, env seed 11) with deterministic actions, the latent updated after every
interaction as in training (:class:`lili.evaluate.Episodes`). A least-squares fit of the
partner's true strategy (``info["strategy"][0]``: Drift's goal g) on z^i over the first 70%
scores R^2 on the rest, and a nearest-neighbour probe (the strategy of the nearest z in the
first 70%) scores how often it names the held-out strategy, overall and outside the commonest
strategy (whose share is what always guessing it scores). The linear probe understates what a
latent carries: in Drift LILI's R^2 is 0.3-0.4 while its nearest neighbour names g right 90%
of the time and 70% outside the wall's goal (a return of the partner, 5% of interactions, is
unknowable from the last interaction, so no latent scores 1 there). The table also gives the
return per interaction, how often the interaction ended across 0 from g (in Drift what the
influencer does every time, the greedy response never) and the mean |x_end - g|. No R^2
("nan") when the partner never changed strategy in the held-out part. Where the env has
discrete strategies (``info["strategy_id"]``, e.g. air hockey's three modes) a second table
gives, per strategy, how often the nearest latent names it when it is the one played: a
strategy the latent does not tell apart scores near 0 there. In Drift z^i can know at most
the goal that interaction i-1 *predicts* (its goal moved one step toward the side where it
ended; a return is unknowable), so for Drift runs a third table scores the nearest-neighbour
probe against that predicted goal, overall and where it is one of the two goals next to the
start (the ones the influencer holds), and lists which of those two were predicted at all.
A fourth table asks whether the encoder could tell apart the goals influence would produce:
the scripted influencer plays 400 interactions (env seed 5) with the run's encoder frozen
(:class:`drift_lagged.FrozenLatentObservation`), and for each goal those interactions predict
it gives the goal the nearest latent of the agent's own play names, and how far those latents
lie from the agent's own (median distance to the nearest; own play against itself beside it),
and how often a nearest-neighbour probe fitted on the first half of those interactions names
the second half's goals (whether the latent tells them apart among themselves; 0.5 is chance).
A fifth table plays 500 interactions of the agent's own policy with its exploration noise (as
in training) and compares the latent's spread within one predicted goal with the distance
between goals, in z and in what z predicts (the decoder's means at the probe inputs that
``lili-prediction-critic`` gives the critic, ``lili.contrib.latents.decoder_predictions``).
Prints the tables and writes ``benchmarks/results/<--name>.json``.
"""

from __future__ import annotations

import argparse
import json

import gymnasium as gym
import numpy as np
from _results import RESULTS, check_result_name
from drift_lagged import FrozenLatentObservation

from lili.agents import load_agent
from lili.contrib.latents import decoder_predictions, probe_inputs
from lili.envs.influence import HELD, make_scripted
from lili.envs.influence.drift import drifted
from lili.envs.spec import load_env_class
from lili.evaluate import Episodes
from lili.play.policy import agent_file_for_run


def sq_dist(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Squared Euclidean distance between every row of ``a`` and every row of ``b``."""
    return ((a[:, None, :] - b[None, :, :]) ** 2).sum(-1)


def nearest_label(z_fit: np.ndarray, labels: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The label of the nearest ``z_fit`` (squared Euclidean distance) for each row of ``z``;
    among equally near ones the commonest label (a categorical latent puts many interactions
    on exactly the same z, and the first of them need not be typical)."""
    d = sq_dist(z, z_fit)
    tied = d <= d.min(1, keepdims=True) + 1e-9
    values, index = np.unique(labels, return_inverse=True)
    votes = tied.astype(np.int64) @ np.eye(len(values), dtype=np.int64)[index]
    return values[votes.argmax(1)]


def nearest_neighbour(z_fit: np.ndarray, g_fit: np.ndarray, z: np.ndarray,
                      g: np.ndarray) -> tuple[float, float, float]:
    """A nonlinear probe: the share of ``g`` that the strategy of the nearest ``z_fit`` gets
    right, overall and outside the most common strategy, and that strategy's share (what
    always guessing it scores)."""
    guess = nearest_label(z_fit, g_fit, z)
    values, counts = np.unique(g, return_counts=True)
    rare = g != values[counts.argmax()]
    hit = guess == g
    return float(hit.mean()), float(hit[rare].mean()) if rare.any() else float("nan"), \
        float(counts.max() / counts.sum())


def recall_per_strategy(z_fit: np.ndarray, id_fit: np.ndarray, z: np.ndarray,
                        ids: np.ndarray) -> dict[int, tuple[float, int]]:
    """For each discrete strategy: how often the nearest ``z_fit`` has it when it is the one
    being played (recall), and how many held-out interactions played it."""
    guess = nearest_label(z_fit, id_fit, z)
    return {int(m): (float(np.mean(guess[ids == m] == m)), int(np.sum(ids == m)))
            for m in np.unique(ids)}


def drift_predicted(ids: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """Drift: the goal id that interaction i-1 predicts for interaction i (i >= 1), i.e. the
    partner's move if it does not return (the first interaction has none: -1)."""
    side = np.where(ends >= 0, 1, -1)
    return np.r_[-1, [drifted(int(i), int(o)) for i, o in
                      zip(ids[:-1], side[:-1], strict=True)]]


def predicted_probe(z: np.ndarray, ids: np.ndarray, ends: np.ndarray, k: int,
                    near: tuple[int, ...]) -> dict:
    """The nearest-neighbour probe (fit on interactions 1..k-1, scored on k..) against
    Drift's predicted goal, overall and where the predicted goal is in ``near``."""
    pred = drift_predicted(ids, ends)
    guess = nearest_label(z[1:k], pred[1:k], z[k:])
    hit, at = guess == pred[k:], np.isin(pred[k:], near)
    return {"knn": float(hit.mean()), "knn_near": float(hit[at].mean()) if at.any()
            else float("nan"), "near_count": int(at.sum()),
            "near_seen": sorted(int(i) for i in np.unique(pred[np.isin(pred, near)]))}


def naming(z_fit: np.ndarray, labels_fit: np.ndarray, z: np.ndarray,
           labels: np.ndarray) -> dict[int, dict]:
    """For each label of ``z``: which labels the nearest ``z_fit`` gives its rows (counts)
    and the median distance of its rows to the nearest ``z_fit``."""
    near = nearest_label(z_fit, labels_fit, z)
    dist = np.sqrt(sq_dist(z, z_fit)).min(1)
    out = {}
    for label in np.unique(labels):
        m = labels == label
        named, counts = np.unique(near[m], return_counts=True)
        out[int(label)] = {"named": {int(a): int(b) for a, b in zip(named, counts, strict=True)},
                           "distance": float(np.median(dist[m]))}
    return out


def own_spacing(z: np.ndarray) -> float:
    """Median distance from each latent to the nearest other one."""
    d = np.sqrt(sq_dist(z, z))
    np.fill_diagonal(d, np.inf)
    return float(np.median(d.min(1)))


def spread(z: np.ndarray, labels: np.ndarray, least: int = 5) -> tuple[float, float]:
    """(within, between): the median over labels with ``least`` or more rows of the RMS
    distance of their latents to their centroid, and of the distance from their centroid to
    the nearest other label's. within << between: the latent is a clean code of the label."""
    keep = [lab for lab in np.unique(labels) if np.sum(labels == lab) >= least]
    centres = np.array([z[labels == lab].mean(0) for lab in keep])
    within = [np.sqrt(((z[labels == lab] - c) ** 2).sum(-1).mean())
              for lab, c in zip(keep, centres, strict=True)]
    d = np.sqrt(sq_dist(centres, centres))
    np.fill_diagonal(d, np.inf)
    between = d.min(1) if len(keep) > 1 else np.array([np.nan])
    return float(np.median(within)), float(np.median(between))


def own_play(episodes: Episodes, n: int) -> dict[str, np.ndarray]:
    """Latent, partner strategy (``goal``, ``id``), end position and return of ``n``
    interactions of ``episodes``' agent, the latent updated after each as in training."""
    rows: dict[str, list] = {"z": [], "goal": [], "id": [], "end": [], "ret": []}
    for _ in range(n):
        rows["z"].append(np.asarray(episodes.acting.z, np.float32))
        rows["goal"].append(float(episodes.info["strategy"][0]))
        rows["id"].append(int(episodes.info.get("strategy_id", -1)))
        done = episodes.play()
        rows["ret"].append(float(done["ret"]))
        rows["end"].append(float(done["traj"]["next_obs"][-1][0]))  # line envs observe [x]
    return {k: np.asarray(v) for k, v in rows.items()}


def noisy_latents(agent, env, n: int, seed: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """(latent, predicted goal id) of ``n`` interactions of the agent's own policy played
    with its exploration noise, as in training."""
    played = own_play(Episodes(agent, env, seed=seed, deterministic=False), n)
    return played["z"][1:], drift_predicted(played["id"], played["end"])[1:]


def influencer_latents(agent, env_id: str, env_kwargs: dict, n: int = 400,
                       seed: int = 5) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(latent, goal id, end position) of ``n`` interactions played by the env's scripted
    influencer, the latent computed by ``agent``'s frozen encoder from the interaction before."""
    env = FrozenLatentObservation(gym.make(env_id, **env_kwargs), agent)
    policy = make_scripted(env_id, "influencer", seed)
    dim = env.observation_space.shape[0] - agent.latent_dim
    zs, ids, ends = [], [], []
    obs, info = env.reset(seed=seed)
    for i in range(n):
        if i:
            obs, info = env.reset()
        zs.append(obs[dim:].copy())
        ids.append(int(info["strategy_id"]))
        done = False
        while not done:
            obs, _, term, trunc, info = env.step(policy(obs[:dim], info))
            done = term or trunc
        ends.append(float(obs[0]))
    return np.asarray(zs), np.asarray(ids), np.asarray(ends)


def probe(run: str, n: int) -> dict:
    """Probe one run (see the module docstring)."""
    path, cfg = agent_file_for_run(run)
    env = load_env_class(cfg["env"])(**cfg.get("env_kwargs", {}))
    agent = load_agent(path, env)
    episodes = Episodes(agent, env, seed=11)
    played = own_play(episodes, n)
    z, g, end, returns = played["z"], played["goal"], played["end"], played["ret"]
    x = np.c_[z, np.ones(n)]
    k = int(0.7 * n)
    w, *_ = np.linalg.lstsq(x[:k], g[:k], rcond=None)
    # A partner held at one strategy (Switch's LILI keeps it in the middle) leaves nothing to
    # explain: no R^2 then.
    var = float(np.var(g[k:]))
    r2 = 1.0 - float(np.mean((x[k:] @ w - g[k:]) ** 2)) / var if var > 1e-12 else float("nan")
    knn, knn_rare, base = nearest_neighbour(z[:k], g[:k], z[k:], g[k:])
    sid = played["id"]
    # Discrete strategies (air hockey's modes): whether the latent tells each one apart.
    recall = recall_per_strategy(z[:k], sid[:k], z[k:], sid[k:]) if np.all(sid >= 0) else {}
    predicted = None
    if cfg["env"] == "lili/InfluenceDrift-v0":
        predicted = predicted_probe(z, sid, end, k, HELD[cfg["env"]])
        zi, idi, endi = influencer_latents(agent, cfg["env"], cfg.get("env_kwargs", {}))
        own = drift_predicted(sid, end)
        pred_i = drift_predicted(idi, endi)[1:]
        predicted["influencer"] = naming(z[1:], own[1:], zi[1:], pred_i)
        half = len(pred_i) // 2  # can the latent tell those goals apart among themselves?
        predicted["influencer_apart"] = float(np.mean(
            nearest_label(zi[1:][:half], pred_i[:half], zi[1:][half:]) == pred_i[half:]))
        predicted["own_spacing"] = own_spacing(z[1:])
        # How much the latent moves within one predicted goal under training's noisy actions,
        # and how much what it predicts moves (the critic's code with
        # lili-prediction-critic).
        zn, goals = noisy_latents(agent, env, min(n, 500))
        predicted["noisy_spread"] = spread(zn, goals)
        code = decoder_predictions(agent.core.decoder, agent.state.model["decoder"],
                                   np.asarray(zn, np.float32),
                                   *probe_inputs(agent.obs_dim, agent.act_dim))
        predicted["prediction_spread"] = spread(np.asarray(code), goals)
    return {"recall_per_strategy": recall, "predicted": predicted, "run": run,
            "algo": cfg["algo"],
            "interactions_trained": int(cfg["interactions"]),
            "probe_r2": r2, "knn": knn, "knn_rare": knn_rare, "base_rate": base,
            "return": float(np.mean(returns)),
            "ends_across": float(np.mean(np.sign(end) != np.sign(g))),
            "end_error": float(np.mean(np.abs(end - g)))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs", nargs="+", help="run folders")
    ap.add_argument("--interactions", type=int, default=1500)
    ap.add_argument("--name", default="latent_probe", help="results file stem")
    args = ap.parse_args()
    check_result_name(ap, args.name)
    if args.interactions < 10:
        ap.error(f"--interactions {args.interactions} is invalid; allowed: an integer >= 10")
    rows = [probe(r, args.interactions) for r in args.runs]
    lines = ["| run | algo | trained | linear R^2 (z -> g) | nearest z: g right | "
             "... outside the commonest g (its share) | return | ends across 0 from g | "
             "mean abs(x_end - g) |", "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['run']} | {r['algo']} | {r['interactions_trained']} | "
                     f"{r['probe_r2']:.2f} | {r['knn']:.2f} | {r['knn_rare']:.2f} "
                     f"({r['base_rate']:.2f}) | {r['return']:.3f} | {r['ends_across']:.2f} | "
                     f"{r['end_error']:.3f} |")
    recalls = [r for r in rows if r["recall_per_strategy"]]
    if recalls:
        n_ids = 1 + max(max(r["recall_per_strategy"]) for r in recalls)
        lines += ["", "Discrete strategies: nearest z names the strategy being played "
                  "(recall per strategy_id, held-out interactions of it in brackets)", "",
                  "| run | " + " | ".join(f"id {m}" for m in range(n_ids)) + " |",
                  "|---|" + "---:|" * n_ids]
        for r in recalls:
            got = r["recall_per_strategy"]
            cells = [f"{got[m][0]:.2f} ({got[m][1]})" if m in got else "—" for m in range(n_ids)]
            lines.append(f"| {r['run']} | " + " | ".join(cells) + " |")
    drift = [r for r in rows if r["predicted"]]
    if drift:
        lines += ["", "Drift: nearest z names the goal the last interaction predicts", "",
                  "| run | right | ... where it is next to the start (held-out count) | "
                  "ids next to the start ever predicted |", "|---|---:|---:|---|"]
        for r in drift:
            p = r["predicted"]
            lines.append(f"| {r['run']} | {p['knn']:.2f} | {p['knn_near']:.2f} "
                         f"({p['near_count']}) | {', '.join(map(str, p['near_seen'])) or '—'} |")
        lines += ["", "Drift: the goals the scripted influencer's interactions predict, named by "
                  "the nearest latent of the agent's own play", "",
                  "| run | predicted goal id (interactions) | named as (count) | distance to "
                  "own latents (own spacing) | told apart |", "|---|---|---|---:|---:|"]
        for r in drift:
            p = r["predicted"]
            for goal, got in p["influencer"].items():
                named = ", ".join(f"{a} ({b})" for a, b in got["named"].items())
                total = sum(got["named"].values())
                lines.append(f"| {r['run']} | {goal} ({total}) | {named} | "
                             f"{got['distance']:.3f} ({p['own_spacing']:.3f}) | "
                             f"{p['influencer_apart']:.2f} |")
        lines += ["", "Drift: the latent under the policy's exploration noise (500 "
                  "interactions): spread within one predicted goal against the distance to "
                  "the nearest other goal (medians over goals)", "",
                  "| run | within | between | within / between | the same for what z predicts "
                  "(D at the probe inputs) |", "|---|---:|---:|---:|---:|"]
        for r in drift:
            within, between = r["predicted"]["noisy_spread"]
            p_within, p_between = r["predicted"]["prediction_spread"]
            lines.append(f"| {r['run']} | {within:.3f} | {between:.3f} | "
                         f"{within / between:.2f} | {p_within / p_between:.2f} |")
    print("\n".join(lines))
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / f"{args.name}.json").write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
