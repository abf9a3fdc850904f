"""Lunar Lander benchmark (Fig. 5): all six algos, landing success and return.

    python benchmarks/lunar_lander.py [--interactions 2000] [--seeds 3] [--jobs 2] [--algos ...]

The same as ``lili reproduce lunar-lander``; see ``benchmarks/_preset.py``.
"""

from _preset import benchmark

if __name__ == "__main__":
    benchmark("lunar-lander", "lunar_lander", __doc__)
