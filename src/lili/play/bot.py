"""Headless sessions against the human-like bot striker: blocks out of shots, beside the paper.

The paper's expert human struck 40 consecutive pucks, aiming away from where the blocker had
blocked the shot before: SAC blocked 18/40, LILI (no influence) 29/40; LILI itself was judged
too brittle to face people. :func:`run_bot` plays the same protocol with :class:`BotStriker`
through the same :class:`GameSession` the page uses (same env, same latent updates, same record).
"""

from __future__ import annotations

from typing import Any

from lili.play.policy import Blocker, ScriptedBlocker
from lili.play.record import SessionRecord
from lili.play.session import GameSession
from lili.play.striker import MODE_NAMES, BotConfig, BotStriker

__all__ = ["run_bot", "PAPER_HUMAN", "PAPER_LILI", "bot_report"]

# The paper's Section 5 ("Playing Against a Human Expert"): blocks out of 40 shots.
PAPER_HUMAN = {"sac": 18, "lili-no-influence": 29}
# ... and why LILI itself has no number there (Section 6).
PAPER_LILI = ("LILI was not played against the human: the paper found it too brittle (it "
              "blocked with its paddle's edges)")


def run_bot(blocker: Blocker | ScriptedBlocker, env_kwargs: dict[str, Any], shots: int = 40,
            config: BotConfig | None = None, seed: int = 0,
            record: SessionRecord | None = None) -> dict[str, Any]:
    """Play ``shots`` shots of the bot against ``blocker``; return the score and every shot."""
    session = GameSession(blocker, env_kwargs, shots, record, None, seed)
    bot = BotStriker(config, seed, session.table.bank_shots)
    rows = []
    try:
        while not session.over:
            result = session.play(bot.next_aim())
            bot.observe(MODE_NAMES.index(result["mode"]), result["side"])
            rows.append(result)
    finally:
        session.close()
    score = session.score()
    return {"blocks": score["blocks"], "shots": score["shots"], "by_mode": score["by_mode"],
            "rows": rows}


def bot_report(algo: str, result: dict[str, Any], config: BotConfig) -> str:
    """One line: blocks/shots against the bot, its settings, and the paper's human study."""
    n = result["shots"]
    line = (f"{algo}: blocked {result['blocks']}/{n} shots of the human-like bot (aim noise "
            f"{config.aim_noise:g} rad, lapse {config.lapse:g}, reaction {config.reaction:g})")
    by = ", ".join(f"{m} {b}/{s}" for m, (b, s) in result["by_mode"].items())
    paper = ", ".join(f"{a} {k}/40" for a, k in PAPER_HUMAN.items())
    return f"{line}; by shot {by}. Paper, against an expert human: {paper}"
