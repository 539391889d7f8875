"""Value types of the model-adapter interface: requests, replies, usage and options.

Adapters are async: :meth:`ModelAdapter.complete` takes a :class:`ModelRequest` and returns a
:class:`ModelResponse` or raises one of the :mod:`bpb_core.errors` model errors. Retries belong to
the runner, never to an adapter.
"""

from __future__ import annotations

import hashlib
import inspect
import math
import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any, Literal

from bpb_core.errors import BadInput


@dataclass(frozen=True)
class TextPart:
    """Plain text in a message."""

    text: str


@dataclass(frozen=True)
class ImagePart:
    """An image in a message; logs refer to it by ``sha256``, never inline."""

    data: bytes = field(repr=False)
    media_type: str = "image/png"

    @property
    def sha256(self) -> str:
        """Hex digest of the image bytes."""
        return hashlib.sha256(self.data).hexdigest()


@dataclass(frozen=True)
class Message:
    """One chat message."""

    role: Literal["system", "user", "assistant"]
    parts: tuple[TextPart | ImagePart, ...]


def prompt_text(messages: Iterable[Message], between: str = "\n") -> str:
    """The text parts of ``messages`` joined by ``between`` (images left out)."""
    return between.join(p.text for m in messages for p in m.parts if isinstance(p, TextPart))


@dataclass(frozen=True)
class ModelRequest:
    """One call to a model.

    Attributes:
        messages: The conversation to send.
        task: Name of the task asked; offline baselines answer by it.
        scene: The scene asked about. Only offline baselines may look at it; an adapter that
            talks to a model must send ``messages`` and nothing else.
        family: Name of the scene's family (offline baselines ask it for predictions).
        simulator: The simulator the dataset's ground truth comes from, as its config names it
            (a name, or ``name:key=value,...`` with its options; offline baselines).
        temperature: Sampling temperature (the paper's protocol uses 0).
        max_tokens: Output token cap, ``None`` for the provider default.
        timeout: Seconds before the call counts as timed out.
        attempt: 1 for the first call of a (scene, task), higher on retries.
        response_schema: The task's answer JSON Schema when the run asks for structured output
            (``--structured-output``); an adapter whose provider accepts a response schema
            sends it, any other ignores it.
    """

    messages: tuple[Message, ...]
    task: str
    scene: Any = None
    family: str | None = None
    simulator: str | None = None
    temperature: float = 0.0
    max_tokens: int | None = None
    timeout: float = 120.0
    attempt: int = 1
    response_schema: dict[str, Any] | None = None


@dataclass(frozen=True)
class Usage:
    """Token counts as the provider reported them (``None`` when not reported)."""

    input_tokens: int | None = None
    output_tokens: int | None = None
    reasoning_tokens: int | None = None
    cached_tokens: int | None = None


@dataclass(frozen=True)
class ModelResponse:
    """A model's reply.

    Attributes:
        text: The reply text.
        usage: Token counts.
        cost: Cost in USD, ``None`` when unknown (never a made-up 0).
        latency: Seconds from request to reply.
        model_id: The provider's model id that answered.
        finish_reason: ``stop``, ``length`` (cut off by the token limit), ``content_filter``
            (refused or blocked by a safety filter) and so on, as OpenAI names them.
        sent: The parameters that actually went on the wire (``None`` when not known).
        dropped: Requested parameters the provider route did not send (``temperature`` ...).
        reasoning: Reasoning text (or reasoning summary) the provider returned, if any.
        refusal: What the model said when it declined (OpenAI's ``refusal``), if it did.
        provider_finish: The provider's own word for how the reply ended (Anthropic
            ``refusal``, Gemini ``SAFETY``, Responses ``incomplete: max_output_tokens``), which
            ``finish_reason`` maps onto OpenAI's vocabulary.
        metadata: The adapter's own measurements about this answer (JSON-ready, flat: names to
            numbers, yes/no values or strings), stored with the answer and summarised by the
            report per horizon; e.g. an offline adapter's error in reading its input.
    """

    text: str
    usage: Usage = Usage()
    cost: float | None = None
    latency: float = 0.0
    model_id: str = ""
    finish_reason: str | None = None
    sent: dict[str, Any] | None = None
    dropped: tuple[str, ...] = ()
    reasoning: str | None = None
    refusal: str | None = None
    provider_finish: str | None = None
    metadata: dict[str, bool | float | str] = field(default_factory=dict)


@dataclass(frozen=True)
class CallCeiling:
    """The most one request may cost, known before it is sent (``--max-cost`` reserves it).

    Attributes:
        input_tokens: The request's input tokens as the adapter counts them.
        input_cost: Their cost in USD.
        output_tokens: The most output tokens (reasoning included) one call may bill: its
            ``max_tokens``, else the model's output limit; ``None`` when no bound is known.
        output_price: USD per output token (the dearer of the output and reasoning prices).
        basis: Where the figures come from, for the user (tokenizer, prices, output limit).
    """

    input_tokens: int
    input_cost: float
    output_tokens: int | None
    output_price: float
    basis: str = ""

    @property
    def output_cost(self) -> float | None:
        """The cost of ``output_tokens`` (``None`` without a bound, unless output is free)."""
        if self.output_tokens is None:
            return 0.0 if self.output_price == 0 else None
        return self.output_tokens * self.output_price


@dataclass(frozen=True)
class AdapterOptions:
    """Options every adapter factory receives; adapters ignore what does not apply to them.

    Attributes:
        api_base: Base URL of an OpenAI-compatible or provider endpoint.
        seed: Seed for adapters with randomness (``baseline:random``).
        prices: Per-model price overrides, USD per token: ``{"input": .., "output": ..}``.
        aliases: Extra model-name aliases, ``{"claude-opus-4.7": "anthropic/..."}``.
        extra: Adapter-specific settings from the config file.
        model_args: Arguments passed through to the provider (``reasoning_effort``,
            ``thinking``, ``max_tokens``, ``temperature``, ``extra_headers`` ...).
        label: Names the option set in run folders and reports (default: made from
            ``model_args``).
    """

    api_base: str | None = None
    seed: int = 0
    prices: dict[str, dict[str, float]] = field(default_factory=dict)
    aliases: dict[str, str] = field(default_factory=dict)
    extra: dict[str, Any] = field(default_factory=dict)
    model_args: dict[str, Any] = field(default_factory=dict)
    label: str | None = None

    def __post_init__(self) -> None:
        if self.api_base is not None:
            check_api_base(self.api_base, "api_base")


def check_api_base(value: object, where: str) -> None:
    """Refuse an ``api_base`` no call could be sent to, before any is: each would be paid for
    in retries and time, only to fail. ``where`` names it (``--api-base``, a run file's key).

    Raises:
        BadInput: One line naming ``where`` and what is wrong with the URL.
    """
    if not isinstance(value, str):
        raise BadInput(f"{where}: expected a string, got {value!r}")
    problem = _url_problem(value)
    if problem is not None:
        raise BadInput(f"{where} {problem}; expected a URL like http://127.0.0.1:8000/v1")


def _url_problem(value: str) -> str | None:
    """What stops ``value`` from being an endpoint's base URL, or ``None``."""
    from urllib.parse import urlsplit

    if not value or any(c.isspace() or not c.isprintable() for c in value):
        return f"{value!r}: empty, or holds a space or a control character"
    try:
        url = urlsplit(value)
        url.port  # noqa: B018 (a port that is no number from 0 to 65535 raises here)
    except ValueError as exc:
        return f"{value!r}: {exc}"
    if url.username is not None or url.password is not None:  # the URL is kept in run.json
        return "holds a user name or password: give keys in the provider's environment variable"
    if url.scheme not in ("http", "https"):
        return f"{value!r}: not an http:// or https:// URL"
    if not url.hostname:
        return f"{value!r}: names no host"
    if url.query or url.fragment or value.endswith(("?", "#")):
        return f"{value!r}: holds a query or fragment (the endpoint's path is appended to it)"
    return None


def split_spec(spec: str, flag: str = "--adapter") -> tuple[str, str]:
    """Split an adapter spec ``name:model`` at the first colon; a spec with no name or no model
    part is a :class:`BadInput` naming ``flag`` (``--adapter``, or a library parameter)."""
    name, sep, model = spec.partition(":")
    if not sep or not name or not model:
        raise BadInput(f"{flag} {spec!r}: expected NAME:MODEL, e.g. baseline:stasis")
    return name, model


def adapter_problem(adapter: object) -> str | None:
    """What keeps ``adapter`` from being a model adapter, or ``None`` when it has an async
    ``complete(request)``: checked once before the first call, so a broken adapter stops the
    run with one line instead of failing every call."""
    if adapter is None:
        return "None"
    kind = type(adapter).__name__
    complete = getattr(adapter, "complete", None)
    if complete is None:
        return f"{article(kind)} {kind} without a complete() method"
    if not inspect.iscoroutinefunction(complete):
        made = "not callable" if not callable(complete) else "not async"
        return f"{article(kind)} {kind} whose complete() is {made}"
    return None


def article(word: str) -> str:
    """``a`` or ``an``, as fits before ``word``."""
    return "an" if word[:1].lower() in "aeiou" else "a"


def known_cost(cost: object) -> float | None:
    """A cost or price in USD if it is one (a finite number >= 0), else ``None`` (unknown): a
    NaN summed into a run's spending would keep ``--max-cost`` from ever stopping it."""
    if isinstance(cost, int | float) and not isinstance(cost, bool) and math.isfinite(cost):
        return float(cost) if cost >= 0 else None
    return None


def non_finite(value: Any, path: str = "") -> tuple[str, float] | None:
    """The first NaN or infinite number in ``value`` (model arguments: nested tables and lists)
    with its dotted path (``thinking.budget_tokens``, ``stop[1]``), or ``None``.

    Model arguments travel as JSON, which has no NaN or infinity: a provider call with one fails
    every time ("Out of range float values are not JSON compliant").
    """
    if isinstance(value, float) and not math.isfinite(value):
        return path, value
    if isinstance(value, dict):
        items: Any = ((f"{path}.{k}" if path else str(k), v) for k, v in value.items())
    elif isinstance(value, list | tuple):
        items = ((f"{path}[{i}]", v) for i, v in enumerate(value))
    else:
        return None
    return next(filter(None, (non_finite(inner, where) for where, inner in items)), None)


_LONE_SURROGATE = re.compile("[\ud800-\udfff]")


def valid_unicode(text: str) -> str:
    """``text`` with every lone surrogate (``"\\udc80"`` in a reply's JSON, or undecodable bytes
    read with ``surrogateescape``) replaced by U+FFFD: such a string has no UTF-8 form, so it
    cannot be written to a file or a web page, nor read back by pydantic."""
    return _LONE_SURROGATE.sub("\ufffd", text)
