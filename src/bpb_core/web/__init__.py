"""Local web apps: people answer the benchmark in the browser (``bpb human``) and runs are
browsed pair by pair (``bpb view``).

Both are Starlette apps served by uvicorn on 127.0.0.1 only, with Jinja2 templates rendered with
autoescaping; the apps themselves answer only requests addressed to 127.0.0.1 or localhost,
however they are served (:func:`loopback_only`). Core knows no task: each
task that people can answer brings its own form widgets
(:class:`~bpb_core.capabilities.AnswersInBrowser`); answers are stored as a normal run through
the run-folder code, so ``bpb report`` puts people beside models. Starlette, uvicorn and Jinja2
come with the ``web`` extra (``pip install 'bpb[web]'``): this module imports none of them
until it is used, so :func:`require_web` can say which is missing.
"""

from __future__ import annotations

import functools
import socket
from typing import TYPE_CHECKING, Any

from bpb_core.errors import BadInput
from bpb_core.model_calls import valid_unicode

if TYPE_CHECKING:
    import jinja2
    from starlette.middleware import Middleware
    from starlette.responses import HTMLResponse

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


def listen(port: int) -> socket.socket:
    """A socket bound to http://127.0.0.1:``port`` (``0``: a free one the system picks), taken
    before anything else is done, so that a port in use is refused before a run folder is made.

    Raises:
        BadInput: The port cannot be bound (another program listens on it): one line naming
            it, with the ``--port`` to choose.
    """
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind((HOST, port))
        sock.listen()  # bound alone, the port could still be bound by another socket
    except OSError as exc:
        sock.close()
        raise BadInput(
            f"--port {port}: cannot listen on {HOST}:{port} ({exc.strerror or exc}); choose "
            "another with --port, or --port 0 for a free one"
        ) from None
    return sock


def url(sock: socket.socket) -> str:
    """The address people open for a socket of :func:`listen` (the port it really got)."""
    return f"http://{HOST}:{sock.getsockname()[1]}/"


def serve(app: Any, sock: socket.socket) -> None:
    """Run ``app`` (built with :func:`loopback_only`) on the socket of :func:`listen` until
    interrupted: the apps have no login, so no other machine may reach them."""
    import uvicorn

    config = uvicorn.Config(app, log_level="warning", access_log=False)
    with sock:
        uvicorn.Server(config).run(sockets=[sock])


@functools.cache
def environment() -> jinja2.Environment:
    """Templates of ``bpb_core/web/templates`` with autoescaping on (also for strings); the
    tasks' form templates are rendered in the same environment."""
    import jinja2

    return jinja2.Environment(
        loader=jinja2.PackageLoader("bpb_core.web", "templates"),
        autoescape=True,
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )


def render(name: str, **context: Any) -> str:
    """Template ``name`` rendered with ``context`` (lone surrogates, from a hand-edited log or
    manifest, as U+FFFD: the page must encode to UTF-8)."""
    return valid_unicode(environment().get_template(name).render(**context))


def error_page(message: str, status: int = 400) -> HTMLResponse:
    """The error page of both apps: ``message`` (one line) with the HTTP ``status``."""
    from starlette.responses import HTMLResponse

    return HTMLResponse(render("error.html", message=message, status=status), status_code=status)


async def plugin_bug_page(request: Any, exc: Exception) -> HTMLResponse:
    """Both apps' handler of a :class:`~bpb_core.errors.PluginBug`: its one line naming the
    plugin, as a 500 page (not a bare 500)."""
    return error_page(str(exc), 500)
