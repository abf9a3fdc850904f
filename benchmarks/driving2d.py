"""Driving (2D) benchmark (Fig. 5): all six algos, success rate and return.

    python benchmarks/driving2d.py [--interactions 1000] [--seeds 3] [--jobs 2] [--algos ...]

The same as ``lili reproduce driving-2d``; see ``benchmarks/_preset.py``.
"""

from _preset import benchmark

if __name__ == "__main__":
    benchmark("driving-2d", "driving2d", __doc__)
