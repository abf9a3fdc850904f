"""lili: Learning Latent Representations to Influence Multi-Agent Interaction (CoRL 2020).

``import lili`` registers the library's envs with Gymnasium (``gym.make("lili/PointMass-v0")``).
"""

__version__ = "0.1.0"

from lili.envs.core import register_envs as _register_envs  # noqa: E402

_register_envs()
