"""Calls into an env from the library's loops (training, resuming, evaluation), each checked.

An env that raises, or returns what a loop cannot use (an observation of another shape, or not
numbers; a step that is not the five values of Gymnasium's API; a reward that is not a number),
stops the loop with one :class:`EnvError` line that names the env, the interaction and the step,
and the env's own message: the same wrapping ``lili check-env`` gives, so that the env's
failure does not read as lili's own (a traceback, JAX's broadcasting message).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from lili.errors import flat, shown

__all__ = ["EnvError", "env_reset", "env_step", "where"]


class EnvError(ValueError):
    """The env raised or returned what the loop cannot use; the message names the env, the
    interaction and the step."""


def where(interaction: int | None, step: int | None = None) -> str:
    """``interaction 3, step 7`` (the parts that are known)."""
    parts = ([] if interaction is None else [f"interaction {interaction}"]) \
        + ([] if step is None else [f"step {step}"])
    return ", ".join(parts) or "start"


def _name(env: gym.Env) -> str:
    """The registered id, else ``module:Class`` (the spec ``lili train`` takes)."""
    spec = getattr(env, "spec", None)
    cls = type(getattr(env, "unwrapped", env))
    return getattr(spec, "id", None) or f"{cls.__module__}:{cls.__qualname__}"


def _failed(env: gym.Env, at: str, what: str) -> EnvError:
    return EnvError(f"env {_name(env)}, {at}: {what}")


def _raised(env: gym.Env, at: str, call: str, e: BaseException) -> EnvError:
    return _failed(env, at, f"{call} raised {type(e).__name__}: {flat(str(e))}")


def _check_obs(env: gym.Env, obs: Any, at: str, call: str) -> Any:
    try:
        arr = np.asarray(obs, np.float32)
    except (TypeError, ValueError):
        raise _failed(env, at, f"{call} returned the observation {shown(obs)}, which is not an "
                      "array of numbers") from None
    shape = getattr(env.observation_space, "shape", None)
    if shape is not None and arr.shape != tuple(shape):
        raise _failed(env, at, f"{call} returned an observation of shape {arr.shape}; the "
                      f"observation space has shape {tuple(shape)}")
    return obs


def env_reset(env: gym.Env, at: str, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
    """``env.reset(**kwargs)``, checked (see the module docstring); ``at`` says where the loop
    is (:func:`where`)."""
    call = f"reset({', '.join(f'{k}={v!r}' for k, v in kwargs.items())})"
    try:
        obs, info = env.reset(**kwargs)
    except (KeyboardInterrupt, EnvError):
        raise
    except Exception as e:
        raise _raised(env, at, call, e) from None
    if not isinstance(info, dict):
        raise _failed(env, at, f"{call} returned info {shown(info)}; allowed: a dict")
    return _check_obs(env, obs, at, call), info


def env_step(env: gym.Env, action: Any, at: str) -> tuple[Any, Any, Any, Any, dict[str, Any]]:
    """``env.step(action)``, checked (see the module docstring); its values as the env gave
    them."""
    try:
        out = env.step(action)
    except (KeyboardInterrupt, EnvError):
        raise
    except Exception as e:
        raise _raised(env, at, "step()", e) from None
    if not isinstance(out, tuple) or len(out) != 5:
        raise _failed(env, at, f"step() returned {shown(out)}; allowed: the 5 values (obs, "
                      "reward, terminated, truncated, info) of Gymnasium's API")
    obs, reward, terminated, truncated, info = out
    try:
        float(reward)  # checked only: the loops sum the env's own number types, as before
    except (TypeError, ValueError):
        raise _failed(env, at, f"step() returned the reward {shown(reward)}, which is not a "
                      "number") from None
    if not isinstance(info, dict):
        raise _failed(env, at, f"step() returned info {shown(info)}; allowed: a dict")
    return _check_obs(env, obs, at, "step()"), reward, terminated, truncated, info
