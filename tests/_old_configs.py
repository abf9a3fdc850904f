"""What releases before some agent fields wrote: shared by the tests that old run folders
still count as done and resume."""

from lili.config import RETIRED_FIELDS

NEW_AGENT_FIELDS = ("random_interactions", "boundary_discount")
"""Agent-config fields added after the first release: a config.yaml may lack them."""


def drop_new_agent_fields(cfg: dict) -> dict:
    """``cfg`` (a parsed config.yaml) as a release before :data:`NEW_AGENT_FIELDS` wrote it."""
    for name in NEW_AGENT_FIELDS:
        del cfg["agent"][name]
    return cfg


def add_retired_fields(cfg: dict, **values) -> dict:
    """``cfg`` as the releases that had the fields now in lili.contrib wrote it (s20-s24: every
    one at its default unless ``values`` says otherwise)."""
    cfg["agent"].update({name: default for name, (default, _) in RETIRED_FIELDS.items()},
                        **values)
    return cfg
