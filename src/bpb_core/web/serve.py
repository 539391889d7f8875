"""Serving an app on the loopback interface only (127.0.0.1): the apps have no login, so no
other machine may reach them."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from bpb_core.errors import BadInput

if TYPE_CHECKING:
    from starlette.middleware import Middleware

HOST = "127.0.0.1"
NAMES = (HOST, "localhost")  # the Host headers the apps answer


def require_web() -> None:
    """Raise :class:`BadInput` naming the extra when Starlette, uvicorn or Jinja2 is missing."""
    import importlib.util

    missing = [m for m in ("starlette", "uvicorn", "jinja2") if importlib.util.find_spec(m) is None]
    if missing:
        raise BadInput(f"the web apps need {', '.join(missing)}: pip install 'bpb[web]'")


def loopback_only() -> Middleware:
    """The middleware every app is built with: it answers only requests addressed to this
    machine by name (``Host`` 127.0.0.1 or localhost, any port); others get a 400. Listening on
    loopback is not enough: a web page whose own name is made to resolve to 127.0.0.1 (DNS
    rebinding) reaches the port, and as the same origin it could read the pages and post
    answers. It is part of the app, not of :func:`serve`, so an app served some other way (a
    library caller's own uvicorn) has it too."""
    from starlette.middleware import Middleware
    from starlette.middleware.trustedhost import TrustedHostMiddleware

    return Middleware(TrustedHostMiddleware, allowed_hosts=list(NAMES))


def serve(app: Any, port: int) -> None:
    """Run ``app`` (built with :func:`loopback_only`) on http://127.0.0.1:``port`` until
    interrupted."""
    import uvicorn

    uvicorn.run(app, host=HOST, port=port, log_level="warning", access_log=False)
