"""Model arguments: their label and record, and what litellm actually sent.

Arguments come from ``--model-arg KEY=VALUE`` or a run file's ``[adapter.args]``; litellm maps
the OpenAI-style ones (``reasoning_effort``, ``max_tokens``, ``temperature``, ``top_p``) onto each
provider and passes provider-native ones (Anthropic's ``thinking``) through. ``extra_headers``
carries extra HTTP headers.

The reply's body is caught the same way, after the HTTP call, for the provider's own finish
reason and a refusal (:func:`verdict`), which litellm's normalised reply loses.

With ``drop_params`` litellm silently leaves out what a model does not take (``temperature`` for
reasoning models), and it maps arguments onto each provider's own fields (``reasoning_effort``
becomes Anthropic's ``output_config.effort`` or Gemini's ``thinkingConfig``). The provider's
request body, caught by a litellm callback just before the HTTP call, is the truth; bpb records
its parameters (never the messages) and names each requested argument that did not reach the
wire.
"""

from __future__ import annotations

import json
import re
from collections import OrderedDict
from collections.abc import Iterator, Mapping
from typing import Any

_SHORT = {"reasoning_effort": "effort", "temperature": "temp"}
# credential-like argument names: api_key, aws_session_token, vertex_credentials (not max_tokens)
_SECRET = re.compile(
    r"secret|passw|credential|(?:^|[_-])(?:key|token|auth\w*|bearer)(?:$|[_-])", re.IGNORECASE
)
_HEADERS = frozenset({"extra_headers", "headers"})
MASK = "***"


def _short_value(value: Any) -> str:
    if isinstance(value, Mapping):
        if "budget_tokens" in value:
            return str(value["budget_tokens"])
        return json.dumps(value, sort_keys=True, separators=(",", ":"))
    return str(value).lower() if isinstance(value, bool) else str(value)


def label(args: Mapping[str, Any], notes: tuple[str, ...] = ()) -> str:
    """A short name of an option set, e.g. ``effort=high,max_tokens=4096`` (empty for none),
    then the provider rules' short notes (``thinking=8000 as effort=high``). Headers and
    credential-like arguments never name a run: the name becomes a folder."""
    parts = [
        f"{_SHORT.get(k, k)}={_short_value(v)}"
        for k, v in sorted(recorded(args).items())
        if k not in _HEADERS and not _SECRET.search(k)
    ]
    return ",".join([*parts, *notes])


def recorded(value: Any) -> Any:
    """``value`` (model arguments, or the parameters sent) as bpb writes it to any file: every
    header value and every credential-like argument (``api_key``, ``aws_secret_access_key``,
    at any depth) is masked, whatever the header is called (an organisation id or a proxy
    token is the user's to share, not bpb's)."""
    if isinstance(value, Mapping):
        return {
            str(k): _masked(v) if str(k) in _HEADERS or _SECRET.search(str(k)) else recorded(v)
            for k, v in value.items()
        }
    if isinstance(value, list | tuple):
        return [recorded(v) for v in value]
    return value


def _masked(value: Any) -> Any:
    if isinstance(value, Mapping):
        return {str(k): MASK for k in value}
    return MASK


def secrets(args: Mapping[str, Any]) -> tuple[str, ...]:
    """The values :func:`recorded` masks, as text: an error message quoting one (litellm
    echoing a header, a proxy its token) is scrubbed with them."""
    found: list[str] = []

    def collect(value: Any, hidden: bool) -> None:
        if isinstance(value, Mapping):
            for k, v in value.items():
                collect(v, hidden or str(k) in _HEADERS or bool(_SECRET.search(str(k))))
        elif isinstance(value, list | tuple):
            for v in value:
                collect(v, hidden)
        elif hidden and value is not None and len(str(value)) >= 4:
            found.append(str(value))

    collect(args, False)
    return tuple(sorted(set(found), key=len, reverse=True))


def scrub(text: str, hidden: tuple[str, ...]) -> str:
    """``text`` with each of ``hidden`` replaced by the mask."""
    for value in hidden:
        text = text.replace(value, MASK)
    return text


_KEEP = 2048  # bodies waiting to be taken; a call takes its own right after it returns
_CONTENT = frozenset(  # the conversation (text and images are never recorded), and tools
    {"messages", "contents", "input", "system", "system_instruction", "systemInstruction", "tools"}
)
# Where an OpenAI-style argument may land on another provider's wire.
_LANDS_AS: dict[str, tuple[str, ...]] = {
    "reasoning_effort": (
        "reasoning_effort",
        "effort",
        "reasoning",
        "thinkingLevel",
        "thinkingBudget",
        "thinking",
    ),
    "thinking": ("thinking", "thinkingConfig", "thinkingBudget", "reasoning"),
    "max_tokens": ("max_tokens", "max_completion_tokens", "max_output_tokens", "maxOutputTokens"),
    "top_p": ("top_p", "topP"),
    "top_k": ("top_k", "topK"),
    "stop": ("stop", "stop_sequences", "stopSequences"),
}
_NOT_IN_BODY = frozenset({"extra_headers", "api_key", "api_version", "extra_body"})

_bodies: OrderedDict[str, dict[str, Any]] = OrderedDict()
_verdicts: OrderedDict[str, tuple[str | None, str | None]] = OrderedDict()


def _kept(store: OrderedDict[str, Any], call_id: str, value: Any) -> None:
    store[call_id] = value
    while len(store) > _KEEP:
        store.popitem(last=False)


def install(litellm: Any) -> None:
    """Register the catching callback with litellm once per process."""
    from litellm.integrations.custom_logger import CustomLogger

    class _Catcher(CustomLogger):
        def log_pre_api_call(self, model: Any, messages: Any, kwargs: Any) -> None:
            call_id = kwargs.get("litellm_call_id")
            body = (kwargs.get("additional_args") or {}).get("complete_input_dict")
            if isinstance(call_id, str) and isinstance(body, Mapping):
                _kept(_bodies, call_id, {k: v for k, v in body.items() if k not in _CONTENT})

        def log_post_api_call(
            self, kwargs: Any, response_obj: Any, start_time: Any, end_time: Any
        ) -> None:
            call_id, reply = kwargs.get("litellm_call_id"), kwargs.get("original_response")
            if isinstance(call_id, str) and isinstance(reply, str):
                _kept(_verdicts, call_id, verdict(reply))

    if not any(type(cb).__name__ == "_Catcher" for cb in litellm.callbacks):
        litellm.callbacks.append(_Catcher())


def verdict(reply: str) -> tuple[str | None, str | None]:
    """The provider's own word for how a reply ended, and the model's refusal text, from the
    reply body of any of the four protocols (``(None, None)`` for a body that is not JSON).

    litellm maps Anthropic's ``stop_reason: refusal`` and Gemini's ``SAFETY`` both onto
    ``content_filter``, and its Responses bridge drops a ``refusal`` item: the body keeps them.
    """
    try:
        body = json.loads(reply)
    except ValueError:
        return None, None
    if not isinstance(body, dict):
        return None, None
    if "stop_reason" in body:  # Anthropic Messages
        return _word(body.get("stop_reason")), None
    if "candidates" in body or "promptFeedback" in body:  # Gemini generateContent
        first = _first(body.get("candidates"))
        blocked = (body.get("promptFeedback") or {}).get("blockReason")
        return _word(first.get("finishReason") or blocked), None
    if body.get("object") == "response":  # OpenAI Responses
        why = (body.get("incomplete_details") or {}).get("reason")
        parts = [p for item in body.get("output") or [] for p in item.get("content") or []]
        refusals = [p.get("refusal") for p in parts if p.get("type") == "refusal"]
        return _word(f"incomplete: {why}" if why else body.get("status")), _word(*refusals[:1])
    first = _first(body.get("choices"))  # OpenAI chat completions
    return _word(first.get("finish_reason")), _word((first.get("message") or {}).get("refusal"))


def _first(items: Any) -> dict[str, Any]:
    return items[0] if isinstance(items, list) and items and isinstance(items[0], dict) else {}


def _word(value: Any = None) -> str | None:
    return value if isinstance(value, str) and value else None


def take(call_id: str) -> tuple[dict[str, Any] | None, tuple[str | None, str | None]]:
    """The parameters sent by the call ``call_id`` (``None`` when litellm logged no body) and
    the :func:`verdict` of its reply (``(None, None)`` when it logged none)."""
    return _bodies.pop(call_id, None), _verdicts.pop(call_id, (None, None))


def _keys(value: Any) -> Iterator[tuple[str, Any]]:
    if isinstance(value, Mapping):
        for key, inner in value.items():
            yield str(key), inner
            yield from _keys(inner)


def dropped(requested: Mapping[str, Any], sent: Mapping[str, Any]) -> tuple[str, ...]:
    """Requested arguments missing from the wire, or sent with another value (``temperature``
    asked as 0 and sent as 1 counts as dropped; so does ``thinking.budget_tokens`` when the
    route sends adaptive thinking instead)."""
    found: dict[str, list[Any]] = {}
    for key, value in _keys(sent):
        found.setdefault(key, []).append(value)
    lost = []
    for name, value in requested.items():
        if name in _NOT_IN_BODY or value is None:
            continue
        missing = not any(n in found for n in _LANDS_AS.get(name, (name,)))
        changed = name in found and not isinstance(value, Mapping) and value not in found[name]
        if missing or changed:
            lost.append(name)
        elif isinstance(value, Mapping):  # thinking = {budget_tokens = 8000}: each leaf counts
            lost += [f"{name}.{k}" for k, v in _keys(value) if v not in found.get(k, [])]
    return tuple(sorted(lost))
