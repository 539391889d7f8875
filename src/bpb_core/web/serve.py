"""Serving an app on the loopback interface only (127.0.0.1): the apps have no login, so no
other machine may reach them."""

from __future__ import annotations

from typing import Any

from bpb_core.errors import BadInput

HOST = "127.0.0.1"


def require_web() -> None:
    """Raise :class:`BadInput` naming the extra when Starlette, uvicorn or Jinja2 is missing."""
    import importlib.util

    missing = [m for m in ("starlette", "uvicorn", "jinja2") if importlib.util.find_spec(m) is None]
    if missing:
        raise BadInput(f"the web apps need {', '.join(missing)}: pip install 'bpb[web]'")


def serve(app: Any, port: int) -> None:
    """Run ``app`` on http://127.0.0.1:``port`` until interrupted."""
    import uvicorn

    uvicorn.run(app, host=HOST, port=port, log_level="warning", access_log=False)
