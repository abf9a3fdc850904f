"""lili: Learning Latent Representations to Influence Multi-Agent Interaction (CoRL 2020)."""

__version__ = "0.1.0"
