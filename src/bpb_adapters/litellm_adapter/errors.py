"""Mapping litellm and HTTP exceptions onto :mod:`bpb_core.errors`, with secrets redacted.

The runner decides what to retry from the bpb error class alone: 429 becomes
:class:`RateLimited` carrying the server's Retry-After, 5xx and unreadable bodies
:class:`ServerError`, timeouts :class:`ModelTimeout`, connections that fail
:class:`ConnectionFailure` (found in the exception's chain: litellm reports a refused
connection as a 500 on the OpenAI and Anthropic routes). What no retry can fix and every call
would meet is a :class:`SetupFailure` naming its cause, which stops the adapter: 401/403
(:class:`AuthenticationFailed`), 404 (the model or the endpoint not found), 400 (an invalid
parameter), 402, a 429 whose quota is spent (``insufficient_quota``), and an import error inside
litellm (a provider route's module missing), whatever litellm wrapped it in. A 400 about one
request alone (its prompt past the context window, its content refused by a policy filter) and
other 4xx are :class:`RequestRejected`: that pair fails, the others go on.
"""

from __future__ import annotations

import email.utils
import os
import re
import time
from typing import Any

from bpb_core.errors import (
    AuthenticationFailed,
    ConnectionFailure,
    ModelError,
    ModelTimeout,
    RateLimited,
    RequestRejected,
    ServerError,
    SetupFailure,
)

_SECRET_NAME = re.compile(r"(KEY|TOKEN|SECRET|PASSWORD)", re.IGNORECASE)
_KEY_SHAPE = re.compile(r"\b(sk|pk|key|AIza)[-_A-Za-z0-9]{16,}")
_MAX_MESSAGE = 500


def redact(text: str, hidden: tuple[str, ...] = ()) -> str:
    """Remove ``hidden`` values (the adapter's header values and credential-like arguments),
    secret environment values and key-shaped tokens from ``text``."""
    for value in hidden:
        text = text.replace(value, "***")
    for name, value in os.environ.items():
        if _SECRET_NAME.search(name) and len(value) >= 8 and value in text:
            text = text.replace(value, "***")
    return _KEY_SHAPE.sub("***", text)


def retry_after(exc: BaseException) -> float | None:
    """Seconds from the Retry-After header of the failed response, if any."""
    headers: Any = getattr(exc, "litellm_response_headers", None)
    if not headers:
        response = getattr(exc, "response", None)
        headers = getattr(response, "headers", None)
    if not headers:
        return None
    value = headers.get("retry-after") or headers.get("Retry-After")
    if value is None:
        return None
    try:
        return max(0.0, float(value))
    except ValueError:
        pass
    try:
        when = email.utils.parsedate_to_datetime(str(value))
    except (TypeError, ValueError):
        return None
    return max(0.0, when.timestamp() - time.time())


def _status(exc: BaseException) -> int | None:
    status = getattr(exc, "status_code", None)
    return status if isinstance(status, int) else None


_QUOTA = ("insufficient_quota", "exceeded your current quota")
_SETUP_STATUS = {
    400: "invalid request (400): a parameter or the request's shape is refused",
    402: "payment required (402): the account has no credit",
    404: "not found (404): check the model name and --api-base",
}


def _spent_quota(exc: BaseException) -> bool:
    """Whether a 429 says the quota is spent (OpenAI's ``insufficient_quota``), not a rate."""
    said = f"{exc} {getattr(exc, 'body', '')} {getattr(exc, 'code', '')}".lower()
    return any(marker in said for marker in _QUOTA)


def _chain(exc: BaseException) -> list[BaseException]:
    """``exc`` and the exceptions it was raised from, nearest first (a few levels: litellm
    wraps the HTTP stack's error in its own, and that in an openai SDK one)."""
    chain: list[BaseException] = []
    seen: BaseException | None = exc
    while seen is not None and len(chain) < 8:
        chain.append(seen)
        seen = seen.__cause__ or seen.__context__
    return chain


def _missing_module(chain: list[BaseException]) -> bool:
    """Whether an import error lies in the chain (however litellm wrapped it)."""
    return any(isinstance(e, ImportError) for e in chain) or "No module named" in str(chain[0])


def _unreachable(chain: list[BaseException]) -> bool:
    """Whether the connection itself failed (refused, reset, DNS, TLS: an ``OSError`` under
    the HTTP stack), which litellm reports on some routes as a 500 ``InternalServerError``."""
    return any(isinstance(e, OSError) and not isinstance(e, TimeoutError) for e in chain)


def map_error(exc: BaseException, hidden: tuple[str, ...] = ()) -> ModelError:
    """The bpb model error for an exception raised by ``litellm.acompletion``; its message
    holds none of ``hidden`` (see :func:`redact`)."""
    from litellm.exceptions import (
        APIConnectionError,
        AuthenticationError,
        ContentPolicyViolationError,
        ContextWindowExceededError,
        PermissionDeniedError,
        RateLimitError,
        Timeout,
    )

    message = redact(" ".join(f"{type(exc).__name__}: {exc}".split()), hidden)[:_MAX_MESSAGE]
    status, chain = _status(exc), _chain(exc)
    if _missing_module(chain):  # retrying cannot install the module
        return SetupFailure("provider module missing", message)
    if isinstance(exc, RateLimitError) or status == 429:
        if _spent_quota(exc):
            return SetupFailure("insufficient quota (429): add credit or raise the limit", message)
        return RateLimited(message, retry_after=retry_after(exc))
    if isinstance(exc, Timeout | TimeoutError):
        return ModelTimeout(message)
    if isinstance(exc, AuthenticationError) or status == 401:
        return AuthenticationFailed("authentication failed (401): check the key", message)
    if isinstance(exc, PermissionDeniedError) or status == 403:
        return AuthenticationFailed("permission denied (403): the key may not use it", message)
    if isinstance(exc, APIConnectionError) or _unreachable(chain):
        return ConnectionFailure(message)
    if isinstance(exc, ContextWindowExceededError | ContentPolicyViolationError):
        return RequestRejected(message)  # about this prompt alone
    if status in _SETUP_STATUS:
        return SetupFailure(_SETUP_STATUS[status], message)
    if status is not None and 400 <= status < 500:
        if status in (408, 409):
            return ServerError(message)  # request timeout / conflict: transient by definition
        return RequestRejected(message)
    # 5xx (with the server's Retry-After, e.g. 503 or Anthropic's 529 overload), invalid bodies
    # and anything unexpected from the HTTP stack: transient, bounded retries
    return ServerError(message, retry_after=retry_after(exc))
