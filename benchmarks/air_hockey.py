"""Air hockey benchmark (Fig. 6): Random, SAC, LILI (no influence), LILI and the Oracle.

    python benchmarks/air_hockey.py [--interactions 1000] [--seeds 3] [--jobs 2] [--algos ...]

Block rate over the last 10% (= the last 100 at 1000 interactions), the striker's modes over
the last 200 and the reward per interaction, beside Sec. 5.3 and Fig. 6. The same as
``lili reproduce air-hockey``; see ``benchmarks/_preset.py``.
"""

from _preset import benchmark

if __name__ == "__main__":
    benchmark("air-hockey", "air_hockey", __doc__)
