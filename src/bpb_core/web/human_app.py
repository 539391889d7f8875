"""The Starlette app of ``bpb human``: one scene at a time, answers posted back as a form.

``GET /`` shows the next unanswered scene (or a closing page), ``POST /answer`` stores it or
answers 400 with the field at fault, ``GET /image/<scene_id>`` serves the scene's input image.
"""

from __future__ import annotations

import time

from markupsafe import Markup
from starlette.applications import Starlette
from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.responses import HTMLResponse, RedirectResponse, Response
from starlette.routing import Route

from bpb_core.errors import PluginBug
from bpb_core.web.human import MAX_FIELDS, MAX_VALUE, FormError, HumanSession
from bpb_core.web.serve import loopback_only
from bpb_core.web.templating import render

# A field's name and value as posted (percent-encoded: up to 12 bytes a character); the parser
# stops reading past it, so a post cannot make the app hold more than MAX_FIELDS of these
# (Starlette's defaults, 1000 fields of 1 MB, let any web page make it hold a gigabyte).
MAX_FIELD_BYTES = 16 * MAX_VALUE + 1024


def human_app(session: HumanSession) -> Starlette:
    """The app answering ``session``'s dataset."""

    async def index(request: Request) -> Response:
        ref = session.next_scene()
        if ref is None:
            return HTMLResponse(render("human_done.html", session=session))
        scene = ref.load()
        width, height = _image_size(ref.image())
        try:
            page = session.page(ref)
            forms = {
                name: Markup(session.form(name, context, width, height))
                for name, context in page.forms.items()
            }
        except PluginBug as exc:  # one line naming the plugin, not a bare 500
            return _bad(str(exc), 500)
        html = render(
            "human.html",
            session=session,
            page=page,
            scene=scene,
            forms=forms,
            shown=f"{time.time():.3f}",
            width=width,
            height=height,
        )
        return HTMLResponse(html)

    async def answer(request: Request) -> Response:
        try:
            form = await request.form(
                max_files=0, max_fields=MAX_FIELDS, max_part_size=MAX_FIELD_BYTES
            )
        except HTTPException as exc:  # too many or too long fields, a malformed body
            return _bad(f"form: {exc.detail}")
        fields = {k: v for k, v in form.multi_items() if isinstance(v, str)}
        if len(fields) != len(form.multi_items()):
            return _bad("form: repeated or file fields")
        try:
            shown = float(fields.get("shown", ""))
        except ValueError:
            return _bad("shown: expected the time the page was shown")
        if not 0 < shown <= time.time() + 5:
            return _bad("shown: not a time this page could have been shown")
        try:
            session.submit(fields, shown)
        except FormError as exc:
            return _bad(str(exc))
        except PluginBug as exc:  # nothing stored
            return _bad(str(exc), 500)
        return RedirectResponse("/", status_code=303)

    async def image(request: Request) -> Response:
        sid = request.path_params["scene_id"]
        for ref in session.order:
            if ref.scene_id == sid:
                return Response(ref.image(), media_type="image/png")
        return _bad(f"scene {sid!r}: not in this session", 404)

    return Starlette(
        routes=[
            Route("/", index),
            Route("/answer", answer, methods=["POST"]),
            Route("/image/{scene_id}", image),
        ],
        middleware=[loopback_only()],
    )


def _bad(message: str, status: int = 400) -> HTMLResponse:
    return HTMLResponse(render("error.html", message=message, status=status), status_code=status)


def _image_size(png: bytes) -> tuple[int, int]:
    import io

    from PIL import Image

    with Image.open(io.BytesIO(png)) as img:
        return img.size
