"""Experiments: one preset per figure or table of the paper, and ``lili reproduce``.

- :mod:`~lili.experiments.presets`: the registry (:data:`PRESETS`).
- :mod:`~lili.experiments.plan`: a preset -> runs, each run's state on disk.
- :mod:`~lili.experiments.costs`: measured per-run costs (``--dry-run``, ETA).
- :mod:`~lili.experiments.runner`: the ``lili train`` command of a run (the one place that
  calls training); :mod:`~lili.experiments.local` and :mod:`~lili.experiments.ray_backend`
  execute it.
- :mod:`~lili.experiments.results`: the preset's report (through :mod:`lili.report`).
- :mod:`~lili.experiments.claims`: the paper's claims per preset (and the influence suite's
  goals), checked PASS / FAIL / too few seeds (``lili reproduce NAME --check-only``);
  :mod:`~lili.experiments.why`: why each FAIL of the committed records fails (the
  explanations beside the sources file, listed under each claim table).
- :mod:`~lili.experiments.page`: ``lili results``, the results page ``docs/results.md`` from
  the committed records; its influence-suite section is
  :mod:`~lili.experiments.influence_page`, and :mod:`~lili.experiments.provenance` words
  where a section's runs come from (settings, sources, ``lili reproduce`` commands).
"""

from lili.experiments.plan import RunSpec, plan, run_status
from lili.experiments.presets import PRESETS, Group, Preset, get_preset
from lili.experiments.reproduce import reproduce

__all__ = ["PRESETS", "Group", "Preset", "RunSpec", "get_preset", "plan", "reproduce",
           "run_status"]
