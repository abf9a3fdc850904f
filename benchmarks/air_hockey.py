"""Air hockey benchmark: Random, SAC, LILI (no influence) and LILI on ``lili/AirHockey-v0``.

    python benchmarks/air_hockey.py [--interactions 1000] [--seeds 3] [--jobs 2]

Prints, beside the paper's robot experiment: block rate over the last 10% of interactions
(= the last 100 at the default budget; paper: random 18%, SAC 44%, LILI 91%), how often the
striker fired left, middle and right over the last 200 interactions (paper: LILI 41% left,
LILI (no influence) uniform) and the final reward per interaction (paper: LILI 1.15 +- 0.05,
LILI (no influence) 1.0 +- 0.05). Writes ``benchmarks/results/air_hockey.{json,md}``, the
success-rate curve and the strike-frequency bars.
"""

from _common import benchmark

if __name__ == "__main__":
    benchmark("air-hockey", "air_hockey", __doc__, interactions=1000,
              algos=["random", "sac", "lili-no-influence", "lili"])
