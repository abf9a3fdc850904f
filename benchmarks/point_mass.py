"""Point Mass benchmark: SAC, Oracle, LILI and LILI (no influence), 3 seeds, beside the paper.

    python benchmarks/point_mass.py [--interactions 2000] [--seeds 3] [--jobs 2]

Prints final performance (mean +- s.e. over seeds of the mean return over the last 10% of
interactions) beside the paper's Table (SAC -5.05, LILI -0.72, Oracle -0.54), writes
``benchmarks/results/point_mass.{json,md}`` and the curves and target heatmap in
``<out>/report/``.
"""

from _common import benchmark

if __name__ == "__main__":
    benchmark("point-mass", "point_mass", __doc__, interactions=2000)
