"""Every number of the paper that this library reproduces, each with where it is printed.

Xie, Losey, Tolsma, Finn, Sadigh: "Learning Latent Representations to Influence Multi-Agent
Interaction", CoRL 2020. Places are given as in the paper's LaTeX source (section titles, the
figure and table labels and their order of appearance there): Fig. 1 front, 2 method, 3 the
simulated tasks, 4 Point Mass results (``fig:sim_results1``), 5 the other simulations
(``fig:sim_results2``), 6 air hockey (``fig:robot``); Table 1 the striker's rule (Appendix C),
Table 2 noisy partners (``table:noisy_opponents``, Appendix E.1), Table 3 history-dependent
partners (``table:history_opponents``, Appendix E.2). Appendix letters follow the order of the
appendix sections (A implementation, B simulated domains, C air hockey, D analysis, E complex
strategies).

:data:`PAPER` is keyed by registered env id (what an env-level report needs);
:data:`PAPER_TABLES` holds the two appendix tables whose rows are partner variants.
"""

from __future__ import annotations

from typing import Any

from lili.report.style import env_key

__all__ = ["PAPER", "PAPER_TABLES", "paper_reference"]

PAPER: dict[str, dict[str, Any]] = {
    "lili/PointMass-v0": {
        "return": {"sac": -5.05, "lili": -0.72, "oracle": -0.54},
        "seeds": 3,
        "source": "Xie et al., CoRL 2020: Table 2 (Appendix E.1), rows Ours-0.0 (-0.7206), SAC "
                  "(-5.047) and Oracle (-0.5434); curves and target heatmap in Fig. 4 (Sec. 5.2)",
    },
    "lili/Driving2D-v0": {
        "text": "LILI and Oracle near 100% success, SAC about 50% or below",
        "success_text": {
            "sac": "about 50% or below",
            "lili": "near 100%",
            "oracle": "near 100%",
        },
        "source": "Xie et al., CoRL 2020: Fig. 5 (Sec. 5.2) and Appendix D.2; no numbers given",
    },
    "lili/LunarLander-v0": {
        "text": "LILI close to the Oracle; SAC about 50% (lands on one pad)",
        "success_text": {"sac": "about 50%", "lili": "close to the Oracle"},
        "source": "Xie et al., CoRL 2020: Fig. 5 (Sec. 5.2) and Appendix D.1; no numbers given",
    },
    "lili/DrivingSteer-v0": {
        "text": "Oracle and LILI (no influence) converge to always passing; SAC about 50% "
                "(mixes lanes); SLAC and LILAC keep choosing the same lane and collide",
        "success_text": {"sac": "about 50%", "oracle": "near 100%",
                         "lili-no-influence": "near 100% (slowly)"},
        "source": "Xie et al., CoRL 2020: Fig. 5 (Sec. 5.2, Driving CARLA) and Appendix D.3; "
                  "no numbers given",
    },
    "lili/AirHockey-v0": {
        "success": {"random": 0.18, "sac": 0.44, "lili": 0.91},
        "return": {"lili": 1.15, "lili-no-influence": 1.0},
        "return_se": {"lili": 0.05, "lili-no-influence": 0.05},
        "strategy_freq": {"lili": {"left": 0.41}, "lili-no-influence": "uniform"},
        "strategy_names": ["left", "middle", "right"],
        "text": "block rate over the last 100 interactions: random 18%, SAC 44%, LILI 91%; "
                "striker over the last 200: LILI 41% left, LILI (no influence) uniform",
        "source": "Xie et al., CoRL 2020: Sec. 5.3 (block rates, strike frequencies) and the "
                  "caption of Fig. 6 (reward per interaction), two Panda arms",
    },
}
"""Reference results of the paper, keyed by registered env id.

``return`` maps algo -> final return (mean over the paper's ``seeds`` seeds). ``text`` is a
qualitative description where the paper gives no numbers; ``success_text`` is the per-algo part
of it that the markdown table shows. ``success`` maps algo -> success rate where the paper gives
one; ``strategy_names`` names the partner's discrete strategies (``strategy_id`` 0, 1, ...).
"""

PAPER_TABLES: dict[str, dict[str, Any]] = {
    "noise": {
        "title": "Point Mass with a noisy partner",
        "source": "Xie et al., CoRL 2020: Table 2 (table:noisy_opponents), Appendix E.1 "
                  "'Agent Strategies with Noise'; final rewards, mean +/- s.e. over 3 seeds",
        "env": "lili/PointMass-v0",
        "parameter": "step_noise",
        "parameter_label": "sigma (times the 0.2 rad step)",
        "algo": "lili",
        "seeds": 3,
        "rows": {0.0: (-0.7206, 0.0061), 0.2: (-0.8563, 0.0539), 0.4: (-1.039, 0.0311),
                 0.6: (-1.188, 0.0520), 0.8: (-1.726, 0.1744), 1.0: (-1.715, 0.0535)},
        "bounds": {"sac": (-5.047, 0.0190), "oracle": (-0.5434, 0.0605)},
        "bounds_note": "the paper aggregates SAC and the Oracle over all noise levels",
    },
    "history": {
        "title": "Point Mass with a partner that reacts to the last N interactions",
        "source": "Xie et al., CoRL 2020: Table 3 (table:history_opponents), Appendix E.2 "
                  "'Agent Strategies with History Dependence'; final rewards, mean +/- s.e. "
                  "over 3 seeds",
        "env": "lili/PointMass-v0",
        "parameter": "history",
        "parameter_label": "N (interactions the partner and LILI's encoder look back)",
        "algo": "lili",
        "seeds": 3,
        "rows": {1: (-0.7206, 0.0061), 3: (-0.8969, 0.0276), 5: (-1.736, 0.1481),
                 7: (-3.232, 0.6576), 9: (-3.046, 0.2468), 11: (-4.486, 0.4979)},
        "bounds": {"sac": (-5.162, 0.0865), "oracle": (-0.5605, 0.0361)},
        "bounds_note": "the paper aggregates SAC and the Oracle over all N > 1",
    },
}
"""The appendix tables whose rows are partner variants: ``rows`` maps the partner parameter's
value to the paper's (mean, s.e.) of LILI's final reward; ``bounds`` gives SAC and the Oracle."""


def paper_reference(env: str) -> dict[str, Any] | None:
    """The :data:`PAPER` entry for ``env`` (registered id or alias), or None."""
    key = env_key(env)
    for env_id, entry in PAPER.items():
        if env_key(env_id) == key:
            return entry
    return None
