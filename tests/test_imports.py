"""The import graph of ``src/lili`` has no cycle, and the layers depend one way only."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parent.parent / "src"

# Layers from the bottom (DESIGN.md "Layout"): a module may import its own layer or lower ones.
LAYERS = [
    ("lili.envs", "lili.nets", "lili.dists", "lili.buffer", "lili.config", "lili.video",
     "lili.metrics_file"),
    ("lili.agents",),
    ("lili.contrib",),
    ("lili.train", "lili.many", "lili.runs", "lili.evaluate"),
    ("lili.experiments", "lili.report", "lili.play"),
    ("lili.cli",),
]


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _graph() -> dict[str, set[str]]:
    """module -> the lili modules it imports, at module level or inside functions."""
    files = {_module_name(p): p for p in SRC.joinpath("lili").rglob("*.py")}
    graph: dict[str, set[str]] = {m: set() for m in files}
    for mod, path in files.items():
        package = mod if path.name == "__init__.py" else mod.rpartition(".")[0]
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    up = package.split(".")[: len(package.split(".")) - node.level + 1]
                    base = ".".join([*up, base] if base else up)
                # `from pkg import name` imports pkg.name when that is a module, else pkg.
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in files else base
                           for a in node.names]
            else:
                continue
            graph[mod].update(t for t in targets if t in files and t != mod)
    return graph


def _layer(mod: str) -> int:
    for i, layer in enumerate(LAYERS):
        if any(mod == p or mod.startswith(p + ".") for p in layer):
            return i
    return -1  # the top-level package: lili/__init__.py


def test_no_import_cycle():
    graph = _graph()
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(m: str) -> None:
        state[m] = 1
        stack.append(m)
        for n in sorted(graph[m]):
            if state.get(n) == 1:
                cycle = stack[stack.index(n):] + [n]
                pytest.fail("import cycle: " + " -> ".join(cycle))
            if n not in state:
                visit(n)
        stack.pop()
        state[m] = 2

    for m in sorted(graph):
        if m not in state:
            visit(m)


# The one upward edge: the facade's ``learn()`` (Stable-Baselines3's surface) hands over to the
# training loop, imported when called; the loop itself depends only on lili.agents.base.
ALLOWED_UP = {("lili.agents.facade", "lili.train")}


def test_dependencies_point_down():
    bad = sorted(f"{m} imports {n}" for m, deps in _graph().items() for n in deps
                 if _layer(m) >= 0 and _layer(n) > _layer(m) and (m, n) not in ALLOWED_UP)
    assert not bad, "upward imports:\n" + "\n".join(bad)


def test_the_agent_protocol_module_is_a_leaf():
    assert not {n for n in _graph()["lili.agents.base"] if n.startswith("lili.agents")}


def test_the_training_loop_knows_agents_only_by_their_protocol():
    assert {n for n in _graph()["lili.train"] if n.startswith("lili.agents")} \
        == {"lili.agents.base"}


def test_the_registry_names_every_algos_module_and_reading_it_imports_no_jax():
    """The registry imports each algo's module by name (so contrib sits above the core it
    subclasses): every name must be a module of the tree, and reading the table (for the
    report's order and the presets) must not import JAX."""
    from lili.agents.registry import TABLE

    files = set(_graph())
    assert {a.module for a in TABLE} <= files
    assert {a.module for a in TABLE if a.module.startswith("lili.contrib")}
    code = ("import sys; from lili.agents.registry import ALGOS, PAPER_ALGOS; "
            "assert 'jax' not in sys.modules, 'jax imported'")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr


def test_core_agents_do_not_import_contrib_or_each_other_for_shared_pieces():
    graph = _graph()
    assert not {n for m, deps in graph.items() if m.startswith("lili.agents")
                for n in deps if n.startswith("lili.contrib")}
    assert "lili.agents.lili" not in graph["lili.agents.lilac"]  # both use lili.agents.latent


@pytest.mark.parametrize("module", ["lili.agents.sac", "lili.agents.registry",
                                    "lili.contrib.latents", "lili.train", "lili.runs",
                                    "lili.evaluate", "lili.cli"])
def test_module_imports_first_in_a_fresh_interpreter(module):
    out = subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr


def test_import_lili_registers_the_envs():
    code = "import gymnasium as gym, lili; gym.make('lili/PointMass-v0').reset(seed=0)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
