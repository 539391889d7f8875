"""``bpb list adapters``: every alias with its provider, key variable, price and api_base."""

from __future__ import annotations

from bpb_adapters.litellm_adapter.aliases import ALIASES, PROVIDERS
from bpb_adapters.litellm_adapter.preflight import bundled_map
from bpb_adapters.litellm_adapter.prices import has_price


def catalog() -> list[tuple[str, str]]:
    """``(alias, description)`` for every alias of the table, in its order."""
    table = bundled_map()
    rows = []
    for alias, model in ALIASES.items():
        provider_id = model.split("/", 1)[0]
        provider = PROVIDERS.get(provider_id)
        price = "price known" if has_price(table, model) else "no price (give one: --prices)"
        where = "" if provider is None else f"; key {' or '.join(provider.env)}"
        base = "" if provider is None else f"; api_base {provider.api_base}"
        rows.append((alias, f"{model} (provider {provider_id}{where}; {price}{base})"))
    return rows
