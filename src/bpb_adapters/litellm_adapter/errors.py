"""Mapping litellm and HTTP exceptions onto :mod:`bpb_core.errors`, with secrets redacted.

The runner decides what to retry from the bpb error class alone: 429 becomes
:class:`RateLimited` carrying the server's Retry-After, 5xx and unreadable bodies
:class:`ServerError`, timeouts :class:`ModelTimeout`, dropped connections
:class:`ConnectionFailure`, 401/403 :class:`AuthenticationFailed` and other 4xx
:class:`RequestRejected`. An import error inside litellm (a provider route's module missing) is
:class:`RequestRejected` too, whatever litellm wrapped it in: it cannot heal by retrying.
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


def map_error(exc: BaseException, hidden: tuple[str, ...] = ()) -> ModelError:
    """The bpb model error for an exception raised by ``litellm.acompletion``; its message
    holds none of ``hidden`` (see :func:`redact`)."""
    from litellm.exceptions import (
        APIConnectionError,
        AuthenticationError,
        PermissionDeniedError,
        RateLimitError,
        Timeout,
    )

    message = redact(" ".join(f"{type(exc).__name__}: {exc}".split()), hidden)[:_MAX_MESSAGE]
    # An import error inside litellm (a provider route's module is missing), whatever litellm
    # wrapped it in: retrying cannot install the module.
    seen: BaseException | None = exc
    for _ in range(5):
        if seen is None:
            break
        if isinstance(seen, ImportError):
            return RequestRejected(message)
        seen = seen.__cause__ or seen.__context__
    if "No module named" in str(exc):
        return RequestRejected(message)
    if isinstance(exc, RateLimitError) or _status(exc) == 429:
        return RateLimited(message, retry_after=retry_after(exc))
    if isinstance(exc, Timeout | TimeoutError):
        return ModelTimeout(message)
    if isinstance(exc, AuthenticationError | PermissionDeniedError):
        return AuthenticationFailed(message)
    if isinstance(exc, APIConnectionError):
        return ConnectionFailure(message)
    status = _status(exc)
    if status is not None and 400 <= status < 500:
        if status in (401, 403):
            return AuthenticationFailed(message)
        if status in (408, 409):
            return ServerError(message)  # request timeout / conflict: transient by definition
        return RequestRejected(message)
    # 5xx (with the server's Retry-After, e.g. 503 or Anthropic's 529 overload), invalid bodies
    # and anything unexpected from the HTTP stack: transient, bounded retries
    return ServerError(message, retry_after=retry_after(exc))
