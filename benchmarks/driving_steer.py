"""Driving (steering) benchmark: SAC, Oracle and LILI on ``lili/DrivingSteer-v0``, 3 seeds.

    python benchmarks/driving_steer.py [--interactions 1000] [--seeds 3] [--jobs 2]

Prints passing success over the last 10% of interactions (mean +- s.e. over seeds) and the wall
time per run beside the paper's description of its CARLA task (Oracle and LILI converge to
always passing; SAC about 50% by mixing lanes), writes
``benchmarks/results/driving_steer.{json,md}`` and the curves.
"""

from _common import benchmark

if __name__ == "__main__":
    benchmark("driving-steer", "driving_steer", __doc__, interactions=1000,
              algos=["sac", "oracle", "lili"])
