"""Envs from a spec: what ``lili train ENV``, ``lili check-env ENV`` and ``lili reproduce`` name.

A spec is ``"package.module:ClassName"`` (an env of one's own), a registered Gymnasium id
(``"lili/PointMass-v0"``) or one of the library's short aliases (``"point-mass"``).
:func:`load_env_class` resolves it to a callable that makes envs, :func:`check_env_kwargs`
checks the options given for it by name, and :func:`make_env` does both and builds the env.
"""

from __future__ import annotations

import functools
import importlib
import inspect
from collections.abc import Callable
from typing import Any

import gymnasium as gym
from gymnasium.envs.registration import load_env_creator

from lili.envs.core import ENV_ALIASES, register_envs

__all__ = ["EnvFactory", "load_env_class", "env_kwarg_names", "check_env_kwargs", "make_env"]

EnvFactory = Callable[..., gym.Env]


def load_env_class(spec: str) -> EnvFactory:
    """Resolve ``spec`` to a callable that makes envs (keyword arguments go to the env).

    ``spec`` is ``"package.module:ClassName"`` (a dotted attribute after the colon is allowed;
    so is Gymnasium's ``"package.module:EnvId-v0"``, which imports the module so that it
    registers the id), a registered Gymnasium id (``"lili/PointMass-v0"``) or one of the
    library's short aliases (``"point-mass"``). Gymnasium ids resolve to a partial of
    ``gymnasium.make``. Raises ``ValueError`` naming the bad value when the module, the
    attribute or the id does not exist.
    """
    if not isinstance(spec, str) or not spec.strip():
        raise ValueError(
            f"env spec {spec!r} is invalid; allowed: 'package.module:ClassName' or a registered "
            f"gymnasium id"
        )
    register_envs()
    if ":" in spec:
        module_name, _, attr = spec.partition(":")
        if not module_name or not attr:
            raise ValueError(
                f"env spec {spec!r} is malformed; expected 'package.module:ClassName'"
            )
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            raise ValueError(
                f"env spec {spec!r}: cannot import module {module_name!r} ({exc})"
            ) from exc
        obj: Any = module
        try:
            for part in attr.split("."):
                obj = getattr(obj, part)
        except AttributeError:
            if attr in gym.registry:
                return functools.partial(gym.make, attr)
            raise ValueError(
                f"env spec {spec!r}: module {module_name!r} has no attribute {attr!r}"
            ) from None
        if not callable(obj):
            raise ValueError(
                f"env spec {spec!r}: {attr!r} is a {type(obj).__name__}, not a class or "
                f"function that makes envs"
            )
        return obj
    env_id = ENV_ALIASES.get(spec, spec)
    if env_id in gym.registry:
        return functools.partial(gym.make, env_id)
    known = sorted(ENV_ALIASES) + sorted(ENV_ALIASES.values())
    raise ValueError(
        f"unknown env {spec!r}; allowed: {', '.join(known)}, another registered gymnasium id "
        f"or 'package.module:ClassName' for an env of your own"
    )


def env_kwarg_names(factory: EnvFactory) -> list[str] | None:
    """The keyword arguments an env factory from :func:`load_env_class` accepts, in order, or
    None when it takes ``**kwargs`` (then any name may be valid and only the env can tell).

    For a Gymnasium id the names are those of its entry point's constructor: ``gymnasium.make``'s
    own options (``max_episode_steps`` and others) are not env options and are not listed.
    """
    target: Any = factory
    if isinstance(factory, functools.partial) and factory.func is gym.make and factory.args:
        entry = gym.spec(factory.args[0]).entry_point
        target = load_env_creator(entry) if isinstance(entry, str) else entry
    try:
        params = inspect.signature(target).parameters.values()
    except (TypeError, ValueError):  # a builtin or C extension without a signature
        return None
    if any(p.kind is p.VAR_KEYWORD for p in params):
        return None
    return [p.name for p in params if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)]


def check_env_kwargs(factory: EnvFactory, kwargs: dict[str, Any], label: str,
                     hidden: tuple[str, ...] = ("render_mode",)) -> None:
    """ValueError naming every unknown key of ``kwargs`` and listing the allowed ones (those in
    ``hidden`` are not listed: the CLI sets ``render_mode`` itself)."""
    names = env_kwarg_names(factory)
    if names is None:
        return
    unknown = [k for k in kwargs if k not in names]
    if unknown:
        allowed = [n for n in names if n not in hidden]
        raise ValueError(
            f"unknown env kwarg(s) {', '.join(map(repr, unknown))} for {label}; allowed: "
            f"{', '.join(allowed) if allowed else 'none (the env takes no options)'}")


def make_env(spec: str, kwargs: dict[str, Any] | None = None,
             render_mode: str | None = None) -> gym.Env:
    """The env ``spec`` names (:func:`load_env_class`), built with ``kwargs`` (and
    ``render_mode`` when given) after checking them by name (:func:`check_env_kwargs`).
    ValueError naming the env and the bad value when the spec or an option does not fit."""
    kwargs = dict(kwargs or {})
    factory = load_env_class(spec)
    check_env_kwargs(factory, kwargs, spec)
    if render_mode is not None:
        kwargs["render_mode"] = render_mode
    try:
        return factory(**kwargs)
    except TypeError as e:
        raise ValueError(f"env {spec} does not accept these kwargs {kwargs}: {e}") from None
    except ValueError as e:  # the env's own check of a value, e.g. step_noise='abc'
        raise ValueError(f"env {spec}: {e}") from None
