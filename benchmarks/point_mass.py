"""Point Mass benchmark (Fig. 4): SAC, SLAC, LILAC, LILI (no influence), LILI and the Oracle.

    python benchmarks/point_mass.py [--interactions 2000] [--seeds 3] [--jobs 2] [--algos ...]

The same as ``lili reproduce point-mass``; see ``benchmarks/_preset.py``.
"""

from _preset import benchmark

if __name__ == "__main__":
    benchmark("point-mass", "point_mass", __doc__)
