"""The Starlette app of ``bpb view``: a filtered list of pairs and one page per pair.

``GET /`` lists pairs (query parameters ``model``, ``task``, ``horizon``, ``stable``,
``verdict``, ``page``), ``GET /pair/<run>/<scene_id>/<task>`` shows one, ``GET /image/...`` and
``GET /overlay/...`` serve its pictures. An unknown filter value is a 400 naming it.
"""

from __future__ import annotations

from urllib.parse import urlencode

from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import HTMLResponse, Response
from starlette.routing import Route

from bpb_core.errors import PluginBug
from bpb_core.web.serve import loopback_only
from bpb_core.web.templating import render
from bpb_core.web.viewer import PAGE_SIZE, QueryError, Viewer


def viewer_app(viewer: Viewer) -> Starlette:
    """The app browsing ``viewer``'s runs."""
    run_ids = {run.label: i for i, run in enumerate(viewer.results.runs)}

    async def index(request: Request) -> Response:
        query = dict(request.query_params)
        try:
            rows, total = viewer.select(query)
        except QueryError as exc:
            return _bad(str(exc))
        page = int(query.get("page") or 1)
        keep = {k: v for k, v in query.items() if k != "page" and v}
        html = render(
            "view_index.html",
            viewer=viewer,
            rows=rows.to_dict(orient="records"),
            run_ids=run_ids,
            total=total,
            page=page,
            pages=max(1, -(-total // PAGE_SIZE)),
            query=keep,
            choices=viewer.choices(),
            link=lambda **change: "?" + urlencode({**keep, **change}),
        )
        return HTMLResponse(html)

    async def pair(request: Request) -> Response:
        p = request.path_params
        try:
            view = viewer.pair(int(p["run"]), p["scene_id"], p["task"])
        except QueryError as exc:
            return _bad(str(exc), 404)
        except PluginBug as exc:  # one line naming the plugin, not a bare 500
            return _bad(str(exc), 500)
        return HTMLResponse(render("view_pair.html", view=view))

    async def image(request: Request) -> Response:
        p = request.path_params
        try:
            return Response(viewer.image(int(p["run"]), p["scene_id"]), media_type="image/png")
        except QueryError as exc:
            return _bad(str(exc), 404)

    async def overlay(request: Request) -> Response:
        p = request.path_params
        try:
            png = viewer.overlay(int(p["run"]), p["scene_id"], p["task"])
        except QueryError as exc:
            return _bad(str(exc), 404)
        except PluginBug as exc:
            return _bad(str(exc), 500)
        if not png:
            return _bad("the scene family draws no picture", 404)
        return Response(png, media_type="image/png")

    return Starlette(
        routes=[
            Route("/", index),
            Route("/pair/{run:int}/{scene_id}/{task}", pair),
            Route("/image/{run:int}/{scene_id}", image),
            Route("/overlay/{run:int}/{scene_id}/{task}", overlay),
        ],
        middleware=[loopback_only()],
    )


def _bad(message: str, status: int = 400) -> HTMLResponse:
    return HTMLResponse(render("error.html", message=message, status=status), status_code=status)
