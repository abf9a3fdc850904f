"""What a trained Flee agent knows and does at the interaction boundary (issue 36, item 3).

    python benchmarks/boundary_probe.py RUN [RUN ...] [--name flee_boundary]

Flee's next slot is a known function of the slot and of where the ego stopped
(:func:`lili.envs.influence.flee.fled`), so every (slot k, end slot k_e) pair is a question with
one right answer. For each pair where the ego stopped within one slot of the partner (short of
it, on it or beyond it: the decisions in which greedy and influencing play differ) a scripted
interaction (run toward g = 0.25 k, end on k_e) is stored, and the RUN's newest checkpoint (a
LILI-family agent) is asked three things about the interaction that follows, whose slot is
k' = fled(k, k_e):

- **decoder**: the slot whose reward its decoder predicts highest (D(s, a = 0, z) over x on a
  1/8 grid, z = E(the stored interaction)): does the latent name k'?
- **policy**: where its deterministic policy stops with that z: on k' (the greedy response),
  one slot beyond it (the influencer's: the partner then steps toward home), or at home when
  k' is home (staying is both greedy and the influencer);
- **critic**: at the policy's last state, the end slot whose best last action has the highest
  Q(s, a, z): does the critic prefer the influencer's end to the greedy one?

Pairs are grouped by what the partner does: it flees (away from home or slipping past the
edge: what a greedy ego causes), steps toward home (the ego stopped beyond it), or is home
next. Prints one table (per run: return over its last 10%, then the shares right per group)
and writes ``benchmarks/results/<--name>.json`` with every pair's answers. Nothing is trained.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

import gymnasium as gym
import jax.numpy as jnp
import numpy as np
from _results import check_result_name, write_result

import lili.envs  # noqa: F401  (registers the envs)
from lili.agents import load_agent
from lili.buffer import InteractionBuffer
from lili.envs.influence.flee import SLOT, SLOTS, SPEED, end_slot, fled
from lili.envs.influence.line import move_to, moved
from lili.play.policy import agent_file_for_run

ENV_ID = "lili/InfluenceFlee-v0"
H = 4
GROUPS = ("flees", "toward home", "home next")


def group_of(k: int, k_next: int) -> str:
    """What the partner did: 'home next', 'toward home' (one slot, on its side) or 'flees'
    (away from home, away from the ego at home, or slipping past the edge to the other side)."""
    if k_next == 0:
        return "home next"
    return "toward home" if k != 0 and k_next == k - np.sign(k) else "flees"


def influencer_end(k: int) -> int:
    """Where the scripted influencer stops with the partner on k: one slot beyond, home at home."""
    return int(np.clip(k + np.sign(k), -SLOTS, SLOTS))


def setup(k: int, k_end: int) -> dict[str, np.ndarray]:
    """An interaction with the partner on k that runs toward it and stops on slot k_end."""
    g, x = SLOT * k, 0.0
    rows: dict[str, list] = {"obs": [], "act": [], "rew": [], "next_obs": []}
    for t in range(H):
        left = H - 1 - t  # steps after this one, each one slot at most
        target = g if left else SLOT * k_end
        target = float(np.clip(target, SLOT * (k_end - left), SLOT * (k_end + left)))
        a = float(move_to(x, target, SPEED)[0])
        x_next = moved(x, a, SPEED)
        for key, v in (("obs", [x]), ("act", [a]), ("rew", -abs(x_next - g)),
                       ("next_obs", [x_next])):
            rows[key].append(v)
        x = x_next
    if end_slot(x) != k_end:
        raise AssertionError(f"setup ({k}, {k_end}) ended on {end_slot(x)}")
    return {key: np.asarray(v, np.float32) for key, v in rows.items()}


class Probe:
    """One agent's answers (module docstring)."""

    def __init__(self, agent) -> None:
        if not agent.core.uses_latent:
            raise ValueError(f"{agent.algo}: the probe needs an agent with a latent")
        if agent.core.horizon != H:
            raise ValueError(f"the probe scripts interactions of {H} steps (Flee's default "
                             f"horizon); this agent was trained at horizon {agent.core.horizon}")
        self.agent, self.core, self.state = agent, agent.core, agent.state
        self.xs = np.linspace(-1.0, 1.0, 17, dtype=np.float32)
        self.acts = np.linspace(-1.0, 1.0, 81, dtype=np.float32)

    def acting_state(self, interaction: dict[str, np.ndarray]):
        buf = InteractionBuffer(2, H, 1, 1)
        buf.add(interaction, np.zeros(1, np.float32))
        return self.agent.next_state(buf)

    def decoded_slot(self, z: np.ndarray) -> int:
        n, st = len(self.xs), self.state
        zb = jnp.broadcast_to(jnp.asarray(z).reshape(1, -1), (n, z.size))
        obs = st.norm.obs(jnp.asarray(self.xs)[:, None])
        out = self.core.decoder.apply(st.model["decoder"], obs, jnp.zeros((n, 1)), zb)
        return end_slot(float(self.xs[int(np.argmax(np.asarray(out[:, -1])))]))

    def critic_ends(self, x: float, z: np.ndarray) -> dict[int, float]:
        """max over last actions of min_j Q(s_{H-1}, a, z), per end slot they reach."""
        st = self.state
        s = self.core._x(st.norm, jnp.asarray([[x]], jnp.float32), H - 1)
        z = jnp.asarray(z).reshape(1, -1)
        s = jnp.concatenate([s, self.core.critic_code(st.model, z)], -1)
        s = jnp.broadcast_to(s, (len(self.acts), s.shape[-1]))
        q = np.asarray(self.core.critic.apply(st.model["critic"], s,
                                              jnp.asarray(self.acts)[:, None]).min(0))
        ends = np.array([end_slot(moved(x, a, SPEED)) for a in self.acts])
        return {int(e): float(q[ends == e].max()) for e in np.unique(ends)}

    def answer(self, k: int, k_end: int) -> dict:
        acting = self.acting_state(setup(k, k_end))
        z = np.asarray(acting.z)
        x, state = 0.0, acting
        for _ in range(H - 1):
            a, state = self.agent.predict(np.array([x], np.float32), state)
            x = moved(x, float(a[0]), SPEED)
        a, _ = self.agent.predict(np.array([x], np.float32), state)
        stop = end_slot(moved(x, float(a[0]), SPEED))
        k_next = fled(k, k_end)
        q = self.critic_ends(x, z)
        greedy, infl = k_next, influencer_end(k_next)
        return {"k": k, "k_end": k_end, "k_next": k_next, "group": group_of(k, k_next),
                "decoded": self.decoded_slot(z), "policy_end": stop,
                "critic_prefers_influencer": (None if greedy == infl or infl not in q
                                              or greedy not in q else q[infl] > q[greedy])}


def load(run: Path) -> tuple[Path, Probe]:
    """(checkpoint folder, probe) of a Flee run folder's newest checkpoint; one error line
    (SystemExit) when ``run`` is no run folder, has no checkpoint, is a run of another env or
    holds an agent the probe cannot ask."""
    try:
        path, cfg = agent_file_for_run(run)
        if cfg["env"] != ENV_ID:
            raise ValueError(f"{run} is a run of {cfg['env']!r}; allowed: a run of {ENV_ID}")
        env = gym.make(ENV_ID, **(cfg["env_kwargs"] or {}))
        return path.parent, Probe(load_agent(path, env))
    except ValueError as e:  # CheckpointError included
        raise SystemExit(f"boundary_probe.py: {e}") from None


def final_return(run: Path) -> float | None:
    path = run / "summary.json"
    return json.loads(path.read_text()).get("final_return") if path.exists() else None


def summarise(answers: list[dict]) -> dict[str, dict[str, float]]:
    out = {}
    for group in GROUPS:
        rows = [r for r in answers if r["group"] == group]
        pref = [r["critic_prefers_influencer"] for r in rows
                if r["critic_prefers_influencer"] is not None]
        out[group] = {
            "pairs": len(rows),
            "decoder_right": float(np.mean([r["decoded"] == r["k_next"] for r in rows])),
            "policy_greedy": float(np.mean([r["policy_end"] == r["k_next"] for r in rows])),
            "policy_influencer": float(np.mean([r["policy_end"] == influencer_end(r["k_next"])
                                                for r in rows])),
            "critic_prefers_influencer": float(np.mean(pref)) if pref else float("nan"),
        }
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", type=Path, help="run folders with checkpoints")
    parser.add_argument("--name", default="flee_boundary", help="results/<name>.json")
    args = parser.parse_args()
    check_result_name(parser, args.name)
    probes = [(run, *load(run)) for run in args.runs]  # every run checked before any is probed
    results = []
    for run, ckpt, probe in probes:
        agent = probe.agent
        answers = [probe.answer(k, e) for k in range(-SLOTS, SLOTS + 1)
                   for e in range(-SLOTS, SLOTS + 1) if abs(e - k) <= 1]
        results.append({"run": str(run), "checkpoint": ckpt.name, "algo": agent.algo,
                        "final_return": final_return(run), "summary": summarise(answers),
                        "answers": answers})
    lines = ["Shares right per group of (slot, end) pairs: decoder names k' / policy stops on k' "
             "(greedy) / policy stops as the influencer / critic prefers the influencer's end.",
             "Pairs per group: " + ", ".join(f"{g} {results[0]['summary'][g]['pairs']}"
                                             for g in GROUPS) + ".",
             "", "| run | return | " + " | ".join(GROUPS) + " |",
             "|---|---:|" + "---|" * len(GROUPS)]
    # Resolved: commonpath refuses a mix of relative and absolute paths.
    base = Path(os.path.commonpath([str(r.resolve()) for r in args.runs]))
    for r in results:
        cells = [" / ".join(f"{s[key]:.2f}" for key in ("decoder_right", "policy_greedy",
                                                          "policy_influencer",
                                                          "critic_prefers_influencer"))
                 for s in (r["summary"][g] for g in GROUPS)]
        ret = "n/a" if r["final_return"] is None else f"{r['final_return']:.3f}"
        run = Path(r["run"])
        name = run.resolve().relative_to(base) if len(results) > 1 else run.name
        lines.append(f"| {name} ({r['checkpoint']}) | {ret} | "
                     + " | ".join(cells) + " |")
    write_result(args.name, "\n".join(lines), runs=results)


if __name__ == "__main__":
    main()
