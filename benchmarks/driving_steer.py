"""Driving (steering) benchmark, the paper's CARLA task (Fig. 5): all six algos.

    python benchmarks/driving_steer.py [--interactions 1000] [--seeds 3] [--jobs 2] [--algos ...]

The same as ``lili reproduce driving-steer``; see ``benchmarks/_preset.py``.
"""

from _preset import benchmark

if __name__ == "__main__":
    benchmark("driving-steer", "driving_steer", __doc__)
