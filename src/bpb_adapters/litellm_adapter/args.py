"""Model arguments passed through to the provider: their label, their record, their merge.

Arguments come from ``--model-arg KEY=VALUE`` or a run file's ``[adapter.args]``; litellm maps
the OpenAI-style ones (``reasoning_effort``, ``max_tokens``, ``temperature``, ``top_p``) onto each
provider and passes provider-native ones (Anthropic's ``thinking``) through. ``extra_headers``
carries extra HTTP headers.
"""

from __future__ import annotations

import json
import re
from collections.abc import Mapping
from typing import Any

_SHORT = {"reasoning_effort": "effort", "temperature": "temp"}
_SECRET = re.compile(r"(key|token|secret|auth|password)", re.IGNORECASE)
_NOT_IN_LABEL = frozenset({"extra_headers", "api_key"})


def _short_value(value: Any) -> str:
    if isinstance(value, Mapping):
        if "budget_tokens" in value:
            return str(value["budget_tokens"])
        return json.dumps(value, sort_keys=True, separators=(",", ":"))
    return str(value).lower() if isinstance(value, bool) else str(value)


def label(args: Mapping[str, Any]) -> str:
    """A short name of an option set, e.g. ``effort=high,max_tokens=4096`` (empty for none)."""
    parts = [
        f"{_SHORT.get(k, k)}={_short_value(v)}"
        for k, v in sorted(args.items())
        if k not in _NOT_IN_LABEL
    ]
    return ",".join(parts)


def recorded(args: Mapping[str, Any]) -> dict[str, Any]:
    """``args`` for run.json: secret-looking header values and any ``api_key`` are masked."""
    out: dict[str, Any] = {}
    for key, value in args.items():
        if key == "api_key":
            out[key] = "***"
        elif key == "extra_headers" and isinstance(value, Mapping):
            out[key] = {h: "***" if _SECRET.search(h) else v for h, v in value.items()}
        else:
            out[key] = value
    return out
