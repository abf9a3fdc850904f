"""What a release before some agent fields wrote: shared by the tests that old run folders
still count as done and resume."""

NEW_AGENT_FIELDS = ("latent_kind", "latent_balance", "random_interactions", "latent_bottleneck",
                    "latent_target", "boundary_gamma", "latent_codes", "boundary_discount",
                    "critic_latent")
"""Agent-config fields added after the first release: a config.yaml may lack them."""


def drop_new_agent_fields(cfg: dict) -> dict:
    """``cfg`` (a parsed config.yaml) as a release before :data:`NEW_AGENT_FIELDS` wrote it."""
    for name in NEW_AGENT_FIELDS:
        del cfg["agent"][name]
    return cfg
