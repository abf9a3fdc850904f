"""Driving (2D) benchmark: SAC, Oracle, LILI and LILI (no influence), 3 seeds.

    python benchmarks/driving2d.py [--interactions 1000] [--seeds 3] [--jobs 2]

Prints final return and success rate over the last 10% of interactions (mean +- s.e. over seeds)
beside the paper's description (LILI and Oracle near 100% success, SAC about 50% or below),
writes ``benchmarks/results/driving2d.{json,md}`` and curves in ``<out>/report/``.
"""

from _common import benchmark

if __name__ == "__main__":
    benchmark("driving-2d", "driving2d", __doc__, interactions=1000)
