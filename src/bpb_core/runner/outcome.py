"""What a reply is, before any parsing: refused, cut at the token cap, empty, or one to parse.

A reply the model declined (a refusal, or one a safety filter stopped), one cut at the token
cap and one with no text hold no answer, and asking again the same way would pay for the same
reply: they are recorded as such (the pair's status is ``refused``, ``cut`` or ``empty``), never
re-asked as if malformed, and scored wrong like a parse error. A cut says which cap cut it: a
cap set too low is a setting of the run, not something the model got wrong.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import Any

from bpb_core.model_calls import ModelResponse
from bpb_core.run_folder import NoAnswer


def unanswered(response: ModelResponse) -> NoAnswer | None:
    """``refused``, ``cut`` or ``empty`` for a reply that holds no answer; ``None`` for one
    to parse. A refusal wins over a cut, a cut over an empty text (a reply whose whole cap
    went on reasoning is cut, not empty)."""
    if response.refusal or response.finish_reason == "content_filter":
        return "refused"
    if response.finish_reason == "length":
        return "cut"
    if not response.text.strip():
        return "empty"
    return None


def _caps(sent: Mapping[str, Any]) -> Iterator[str]:
    for key, value in sent.items():
        if isinstance(value, Mapping):
            yield from _caps(value)
        elif "max" in key.lower() and "token" in key.lower():
            yield f"{key}={value}"


def token_cap(response: ModelResponse, asked: int | None) -> str:
    """The cap a cut reply met, as sent (``max_tokens=4000``), else as the run asked it, else
    the provider's default."""
    sent = next(_caps(response.sent or {}), None)
    if sent is not None:
        return sent
    return f"max_tokens={asked}" if asked is not None else "the provider's default max tokens"


def unanswered_error(kind: NoAnswer, response: ModelResponse, asked: int | None) -> str:
    """The one line a refused, cut or empty reply records as its error."""
    finish = response.provider_finish or response.finish_reason
    if kind == "refused":
        said = f": {response.refusal}" if response.refusal else ""
        return f"refused by the model or its safety filter (finish {finish}){said}"
    if kind == "cut":
        cap = token_cap(response, asked)
        setting = "a setting of the run, raise --max-tokens"
        return f"cut at the token cap ({cap}, finish {finish}): {setting}"
    return f"empty reply (finish {finish})"
