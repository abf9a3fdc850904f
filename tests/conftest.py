"""Suite-wide settings: one JAX compilation cache for the whole run, and the longest files first.

Most of the suite's time is XLA compiling the agents' update programs, and the same program is
compiled again in every process that runs it: both pytest-xdist workers and each ``lili``
subprocess a test starts (``lili train``, ``lili reproduce`` and its runs, Ray's workers). A
persistent compilation cache in one temporary folder, made for this run and removed after it,
lets each program compile once per run: a process that meets it again loads the executable
XLA wrote (the same code, so the same numbers), and a test that checks numbers still checks
them. A cache that is already set (``JAX_COMPILATION_CACHE_DIR``) is left as it is.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections import Counter

import pytest

# Files whose time is a few long tests or a long fixture but that hold few tests, so that
# pytest-xdist's own order (most tests first) would start them last and one worker would run
# them alone at the end. They start first; the rest follow with the most tests first (xdist's
# rule), one test class of tests/test_contract.py (one algo) being one unit. ``make test``
# runs ``-n 2 --dist loadscope --no-loadscope-reorder`` to keep this order. From the
# --durations of 2026-12-04 and the files' CPU-seconds of 2026-12-05 (measured alone, under
# load: test_many.py 154, test_reproduce.py 118 and its Ray sweep's own processes, test_lilac.py
# 122, test_slac.py 111; test_jax_train.py's default tests take a second).
LONGEST_FIRST = (
    "test_reproduce.py",
    "test_many.py",
    "test_lilac.py",
    "test_slac.py",
)

_CACHE_OWNER = "LILI_TESTS_JAX_CACHE"  # set when this run made the folder (and removes it)


def pytest_configure(config: pytest.Config) -> None:
    if hasattr(config, "workerinput") or os.environ.get("JAX_COMPILATION_CACHE_DIR"):
        return  # an xdist worker inherits the controller's folder through the environment
    folder = tempfile.mkdtemp(prefix="lili-tests-jax-cache-")
    settings = {
        "JAX_COMPILATION_CACHE_DIR": folder,
        # Every compile is cached: the agents' programs are many short compiles, not a few long.
        "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS": "0",
    }
    # No size limit (JAX_COMPILATION_CACHE_MAX_SIZE): with one, every write lists and stats the
    # whole folder under a lock to find what to evict, so a run's thousands of entries made each
    # compile slower as the folder grew (measured: test_buffer.py's eager ops 80 s in an empty
    # folder, 560 s beside 10,000 entries; 44 s without the limit). Without the lock a process
    # could read an entry another is still writing: JAX then warns and compiles anew (the
    # same executable), so a torn read costs a compile, never a wrong number.
    settings[_CACHE_OWNER] = folder
    # Set before any JAX import (the test modules import it later; workers and subprocesses read
    # it from the environment they inherit).
    os.environ.update(settings)


def pytest_unconfigure(config: pytest.Config) -> None:
    if hasattr(config, "workerinput"):
        return
    folder = os.environ.pop(_CACHE_OWNER, None)
    if folder:
        shutil.rmtree(folder, ignore_errors=True)


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    def unit(item: pytest.Item) -> str:  # what --dist loadscope keeps on one worker
        return item.nodeid.rsplit("::", 1)[0]

    size = Counter(unit(item) for item in items)

    def rank(item: pytest.Item) -> tuple[int, int]:
        name = item.path.name
        first = LONGEST_FIRST.index(name) if name in LONGEST_FIRST else len(LONGEST_FIRST)
        return first, -size[unit(item)]

    items.sort(key=rank)  # stable: a unit's tests keep their order
