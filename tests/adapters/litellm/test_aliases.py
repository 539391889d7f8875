"""Every alias of the paper's models against the pinned litellm: the provider resolves, and the
price is known, or its absence is what docs/providers.md says."""

from __future__ import annotations

import pytest

from bpb_adapters.litellm_adapter.adapter import _import_litellm
from bpb_adapters.litellm_adapter.aliases import ALIASES, PAPER_MODELS, PROVIDERS, provider_of
from bpb_adapters.litellm_adapter.prices import has_price
from support.paths import DOCS

# Not in litellm 1.106.2's bundled price map: docs/providers.md says so, --prices fills in.
UNPRICED = {"qwen3-vl-plus", "qwen3.5-plus", "qwen3.6-plus", "doubao-seed-1.8",
            "doubao-seed-2.0-pro"}  # fmt: skip


@pytest.mark.parametrize("alias", list(ALIASES))
def test_alias_resolves_to_a_provider_with_a_known_key_variable(alias: str) -> None:
    litellm = _import_litellm()
    model = ALIASES[alias]
    provider = provider_of(litellm, model)
    assert provider == model.split("/", 1)[0] and provider in PROVIDERS
    found = litellm.validate_environment(model=model)  # litellm agrees on the key variable
    assert (
        set(found["missing_keys"]) <= set(PROVIDERS[provider].env) or found["keys_in_environment"]
    )
    assert has_price(litellm.model_cost, model) == (alias not in UNPRICED)


def test_docs_name_every_paper_alias_and_every_unpriced_one() -> None:
    text = (DOCS / "providers.md").read_text(encoding="utf-8")
    assert all(f"`{alias}`" in text for alias, _ in PAPER_MODELS)
    assert all(f"{alias}` (no price" in text for alias in UNPRICED)
    assert all(var in text for p in PROVIDERS.values() for var in p.env)
