"""YAML of bounded size, checked before any Python object is built.

A YAML alias repeats what its anchor names, so 380 bytes of nested aliases ("billion laughs")
name 10**9 values: PyYAML builds them as shared references at once, but anything that walks
them (a repr for an error message, a comparison, a dump) runs for minutes and gigabytes.
:class:`BoundedComposer` refuses a document, before it is constructed, when its text is longer
than the loader's ``max_chars``, when it names more than ``MAX_YAML_VALUES`` values with its
aliases expanded, or when it nests deeper than ``MAX_YAML_DEPTH``: as a :class:`YAMLTooLarge`
(a ``yaml.YAMLError``), which every reader already reports as one line.
"""

from __future__ import annotations

from typing import Any

import yaml

__all__ = ["BoundedComposer", "BoundedSafeLoader", "YAMLTooLarge", "check_yaml", "safe_load",
           "yaml_problem", "MAX_YAML_VALUES", "MAX_YAML_DEPTH", "MAX_YAML_CHARS",
           "MAX_VALUE_CHARS"]

MAX_YAML_VALUES = 10_000
"""Most values (scalars, lists and mappings, aliases expanded) in one YAML document."""
MAX_YAML_DEPTH = 50
"""Deepest nesting of lists and mappings."""
MAX_YAML_CHARS = 1_000_000
"""Longest YAML text read from a file (a config is a few hundred characters)."""
MAX_VALUE_CHARS = 10_000
"""Longest YAML value given on the command line (``--env-kwarg``, ``--set``)."""


class YAMLTooLarge(yaml.YAMLError):
    """A YAML text refused for its size, before it was built."""


def _expanded_size(root: yaml.Node) -> int:
    """Values under ``root`` with aliases expanded, counted without expanding them (each shared
    node once); YAMLTooLarge past the bounds or on a recursive alias."""
    sizes: dict[int, int] = {}
    # Iterative post-order walk: (node, depth, children done?).
    stack: list[tuple[yaml.Node, int, bool]] = [(root, 1, False)]
    open_: set[int] = set()
    while stack:
        node, depth, done = stack.pop()
        if depth > MAX_YAML_DEPTH:
            raise YAMLTooLarge(f"it nests deeper than {MAX_YAML_DEPTH} levels; allowed: at most "
                               f"{MAX_YAML_DEPTH}")
        children: list[yaml.Node] = []
        if isinstance(node, yaml.SequenceNode):
            children = list(node.value)
        elif isinstance(node, yaml.MappingNode):
            children = [n for pair in node.value for n in pair]
        if done:
            open_.discard(id(node))
            total = 1 + sum(sizes[id(c)] for c in children)
            if total > MAX_YAML_VALUES:
                raise YAMLTooLarge(f"it names more than {MAX_YAML_VALUES} values (its aliases "
                                   "repeat what their anchors name); allowed: at most "
                                   f"{MAX_YAML_VALUES}")
            sizes[id(node)] = total
            continue
        if id(node) in sizes:
            continue
        if id(node) in open_:
            raise YAMLTooLarge("an alias refers to a value that contains it (a recursive "
                               "structure); allowed: aliases to finished values only")
        open_.add(id(node))
        stack.append((node, depth, True))
        stack.extend((c, depth + 1, False) for c in children if id(c) not in sizes)
    return sizes[id(root)]


class BoundedComposer:
    """Mixin for a PyYAML loader (before it in the bases): refuses, before constructing, a text
    longer than ``max_chars`` and a document past ``MAX_YAML_VALUES`` or ``MAX_YAML_DEPTH``."""

    max_chars = MAX_YAML_CHARS

    def __init__(self, stream: Any) -> None:
        if isinstance(stream, (str, bytes)) and len(stream) > self.max_chars:
            raise YAMLTooLarge(f"it is {len(stream)} characters long; allowed: at most "
                               f"{self.max_chars}")
        super().__init__(stream)  # type: ignore[call-arg]

    def compose_document(self) -> yaml.Node | None:
        try:
            node = super().compose_document()  # type: ignore[misc]
        except RecursionError:
            raise YAMLTooLarge(f"it nests deeper than {MAX_YAML_DEPTH} levels; allowed: at "
                               f"most {MAX_YAML_DEPTH}") from None
        if node is not None:
            _expanded_size(node)
        return node


class BoundedSafeLoader(BoundedComposer, yaml.SafeLoader):
    """PyYAML's safe loader with the bounds of :class:`BoundedComposer`."""


class _ValueLoader(BoundedComposer, yaml.SafeLoader):
    max_chars = MAX_VALUE_CHARS


def check_yaml(text: str, max_chars: int = MAX_YAML_CHARS) -> None:
    """YAMLTooLarge when ``text`` is past the bounds (``max_chars``, ``MAX_YAML_VALUES``,
    ``MAX_YAML_DEPTH``). Only composes the text: malformed YAML is left to the reader that
    loads it, which reports it with its line and column."""
    loader = _ValueLoader if max_chars == MAX_VALUE_CHARS else BoundedSafeLoader
    if isinstance(text, (str, bytes)) and len(text) > max_chars:
        raise YAMLTooLarge(f"it is {len(text)} characters long; allowed: at most {max_chars}")
    try:
        for _ in yaml.compose_all(text, Loader=loader):
            pass
    except YAMLTooLarge:
        raise
    except yaml.YAMLError:
        return


def safe_load(text: str) -> Any:
    """``yaml.safe_load`` within the bounds (YAMLTooLarge past them)."""
    return yaml.load(text, Loader=BoundedSafeLoader)  # noqa: S506 - a SafeLoader


def yaml_problem(e: yaml.YAMLError) -> str:
    """One line: where and what (PyYAML's own message spans several lines with a snippet)."""
    if isinstance(e, yaml.MarkedYAMLError):
        mark = e.problem_mark or e.context_mark
        where = f"line {mark.line + 1}, column {mark.column + 1}: " if mark else ""
        context = f" ({e.context})" if e.context else ""
        return f"{where}{e.problem or 'malformed'}{context}"
    return str(e).splitlines()[0] if str(e) else type(e).__name__
