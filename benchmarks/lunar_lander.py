"""Lunar Lander benchmark: SAC, Oracle and LILI on ``lili/LunarLander-v0``, 3 seeds.

    python benchmarks/lunar_lander.py [--interactions 600] [--seeds 3] [--jobs 2]

Prints landing success (within 0.1 of the pad) and return over the last 10% of interactions
(mean +- s.e. over seeds) and the wall time per run beside the paper's description (LILI close
to the Oracle; SAC about 50%, the no-information bound: the pad alternates and SAC cannot know
which one is next), writes ``benchmarks/results/lunar_lander.{json,md}`` and the curves.
"""

from _common import benchmark

if __name__ == "__main__":
    benchmark("lunar-lander", "lunar_lander", __doc__, interactions=600,
              algos=["sac", "oracle", "lili"])
