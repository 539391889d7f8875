"""``bpb human``: a person's answering session (which scene comes next, the page it shows, turning
a posted form into stored answers) and the Starlette app that serves it, one scene at a time.

``GET /`` shows the next unanswered scene (or a closing page), ``GET /?scene=<id>`` a scene
answered before (to see or change its answer: "back"), ``POST /answer`` stores a scene's answers
or answers 400 with the field at fault, ``POST /skip`` puts the scene asked after the others,
``POST /undo`` removes the answers saved last and asks that scene again, ``GET /image/<scene_id>``
serves the scene's input image. The scenes come in an order shuffled by the seed; a (scene, task)
answered before is not asked again, so closing the browser and starting again resumes. Every
posted field is checked before anything is stored: a bad form stores nothing and says which field
is wrong, and a task's form refuses an untouched page (no answer is "nothing happens" by
default). The page keeps its draft in the browser (``localStorage``, under the run folder's
key), so a reload, the browser's back button after a refused post, or a page reloaded after the
app restarts brings back what was ticked and placed. Each page carries the session's random
token, so a page of another site cannot post answers into the run.

A task's browser form hooks (:class:`~bpb_core.capabilities.AnswersInBrowser`) are called
checked: each runs under :func:`~bpb_core.errors.blamed` and its value is checked, so a task's
mistake is one line naming its plugin (:class:`~bpb_core.errors.PluginBug`, shown as an error
page) instead of a bare 500, or an answer stored that is no answer.
"""

from __future__ import annotations

import contextlib
import io
import json
import random
import re
import secrets
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any
from urllib.parse import quote

from markupsafe import Markup
from PIL import Image
from starlette.applications import Starlette
from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.responses import HTMLResponse, RedirectResponse, Response
from starlette.routing import Route

from bpb_core.capabilities import AnswersInBrowser
from bpb_core.errors import BadInput, ParseFailure, PluginBug, blamed, named
from bpb_core.interfaces import PromptOptions
from bpb_core.model_calls import prompt_text, valid_unicode
from bpb_core.plugin_calls import parsed_answer, prompt_messages
from bpb_core.run_folder import (
    AttemptLog,
    answer_path,
    completed,
    read_attempts,
    write_answer,
    write_json_atomic,
)
from bpb_core.runner.manifest import start_manifest
from bpb_core.runner.options import RunOptions
from bpb_core.runner.scenes import SceneRef, asking
from bpb_core.runner.state import Tally
from bpb_core.web import environment, error_page, loopback_only, plugin_bug_page, render

if TYPE_CHECKING:
    from bpb_core.interfaces import Task
    from bpb_core.registry import Registry


NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")
MAX_FIELDS = 200
MAX_VALUE = 200
MAX_MS = 24 * 3600 * 1000
# A field's name and value as posted (percent-encoded: up to 12 bytes a character); the parser
# stops reading past it, so a post cannot make the app hold more than MAX_FIELDS of these
# (Starlette's defaults, 1000 fields of 1 MB, let any web page make it hold a gigabyte).
MAX_FIELD_BYTES = 16 * MAX_VALUE + 1024
SKIPPED = "human_skipped.json"
"""The run folder's file of the scenes a person skipped, in the order skipped."""
RESERVED = ("prefix", "image_width", "image_height")
"""Template values core adds to a task's :meth:`~AnswersInBrowser.form_context`."""


class FormError(ValueError):
    """A posted form that cannot be stored; the message names the field."""


@dataclass(frozen=True)
class Page:
    """What the page of one scene shows."""

    ref: SceneRef
    prompts: dict[str, str]
    forms: dict[str, dict[str, Any]]
    done: int
    total: int
    back: str | None = None
    """The scene answered before this one (``None``: the first)."""
    answered: bool = False
    """The scene was answered before: saving changes its answer."""


@dataclass
class HumanSession:
    """One person answering a dataset into a run folder (adapter ``human:<name>``)."""

    data: Path
    run_dir: Path
    name: str
    registry: Registry
    options: RunOptions = field(default_factory=RunOptions)
    seed: int = 0
    token: str = field(default_factory=lambda: secrets.token_hex(16), init=False, repr=False)
    order: list[SceneRef] = field(default_factory=list, init=False)
    tasks: dict[str, Task] = field(default_factory=dict, init=False)
    skipped: list[str] = field(default_factory=list, init=False)
    """Scenes skipped, asked after the others in the order skipped (kept in ``SKIPPED`` of the
    run folder, so a restart keeps them last)."""

    def __post_init__(self) -> None:
        if not NAME.match(self.name):
            raise BadInput(f"--name {self.name!r}: use letters, digits, '_', '.' or '-'")
        ask = asking(self.data, self.options, self.registry)
        self.options = ask.options
        self.tasks = ask.tasks
        unable = [n for n, t in self.tasks.items() if not isinstance(t, AnswersInBrowser)]
        if unable:
            raise BadInput(f"--tasks: {', '.join(unable)} cannot be answered in the browser")
        self.order = list(ask.scenes)
        if ask.family.input_image is not None:
            for ref in self.order:  # a damaged image stops the session now, not on its page
                ref.image()
        random.Random(f"human:{self.seed}").shuffle(self.order)
        with contextlib.suppress(OSError, ValueError):  # none skipped yet, or not readable
            ids = {ref.scene_id for ref in self.order}
            self.skipped = [s for s in json.loads((self.run_dir / SKIPPED).read_text()) if s in ids]
        count = len(self.order)
        start_manifest(self.run_dir, self.spec, self.data, self.options, self.registry, count)

    @property
    def spec(self) -> str:
        """The run's adapter name, ``human:<name>``."""
        return f"human:{self.name}"

    @property
    def draft_key(self) -> str:
        """The browser's key of this run's drafts: the same across restarts of the app."""
        return f"bpb-human:{self.run_dir.resolve()}"

    def next_scene(self) -> SceneRef | None:
        """The first scene in the order with a task not yet answered, skipped ones after the
        others (``None`` when done)."""
        done = completed(self.run_dir)
        open_ = [r for r in self.order if any((r.scene_id, t) not in done for t in self.tasks)]
        later = {sid: n for n, sid in enumerate(self.skipped)}
        last = len(later)
        return min(open_, key=lambda r: later.get(r.scene_id, -1) - last, default=None)

    def scene(self, scene_id: str) -> SceneRef | None:
        """The scene ``scene_id`` of this session (``None``: not one of its scenes)."""
        return next((ref for ref in self.order if ref.scene_id == scene_id), None)

    def history(self) -> list[SceneRef]:
        """The scenes answered in full, in the order their answers were saved last."""
        done = completed(self.run_dir)
        full = {r.scene_id for r in self.order if all((r.scene_id, t) in done for t in self.tasks)}
        saved: dict[str, float] = {}
        for entry in read_attempts(self.run_dir):
            sid = entry.get("scene_id")
            if sid in full and isinstance(entry.get("time"), float):
                saved[sid] = max(saved.get(sid, 0.0), entry["time"])
        answered = [r for r in self.order if r.scene_id in full]
        return sorted(answered, key=lambda r: saved.get(r.scene_id, 0.0))

    def skip(self, fields: Mapping[str, str]) -> None:
        """Ask the scene being asked after the others.

        Raises:
            FormError: Not this session's page, or not the scene being asked.
        """
        self._check_token(fields)
        ref = self.next_scene()
        if ref is None or fields.get("scene") != ref.scene_id:
            raise FormError("scene: not the scene being asked (answered already, or stale page)")
        self.skipped = [sid for sid in self.skipped if sid != ref.scene_id] + [ref.scene_id]
        write_json_atomic(self.run_dir / SKIPPED, self.skipped)

    def undo(self, fields: Mapping[str, str]) -> SceneRef:
        """Remove the answers saved last; returns their scene, to be asked again.

        Raises:
            FormError: Not this session's page, or nothing answered yet.
        """
        self._check_token(fields)
        history = self.history()
        if not history:
            raise FormError("undo: nothing answered yet in this run")
        ref = history[-1]
        for task in self.tasks:
            answer_path(self.run_dir, ref.key, task).unlink(missing_ok=True)
        return ref

    def _check_token(self, fields: Mapping[str, str]) -> None:
        if not secrets.compare_digest(fields.get("token", ""), self.token):
            raise FormError(
                "token: not this session's page (another site, or the app restarted: reload "
                "the page, its draft is kept)"
            )

    def page(self, ref: SceneRef) -> Page:
        """The prompts (exactly as a model gets them) and the task forms' values of ``ref``.

        Raises:
            PluginBug: A task's messages() or form_context() raised or returned something
                else than it should, naming its plugin.
        """
        scene, image = ref.load(), ref.image()
        prompts, forms = {}, {}
        for name, task in self.tasks.items():
            origin = self.registry.origin("task", name)
            messages = prompt_messages(task, origin, scene, image, self._prompt_options(name))
            prompts[name] = prompt_text(messages)
            assert isinstance(task, AnswersInBrowser)
            forms[name] = form_context(task, origin, scene, image)
        history = [r.scene_id for r in self.history()]
        answered = ref.scene_id in history
        before = history[: history.index(ref.scene_id)] if answered else history
        back = before[-1] if before else None
        return Page(ref, prompts, forms, len(history), len(self.order), back, answered)

    def form(self, task: str, context: dict[str, Any], width: int, height: int) -> str:
        """The HTML of ``task``'s form on a page (``context`` from :meth:`page`; the input
        image ``width`` by ``height`` pixels).

        Raises:
            PluginBug: The task's form template is no str or does not render, naming its plugin.
        """
        component = self.tasks[task]
        assert isinstance(component, AnswersInBrowser)
        origin = self.registry.origin("task", task)
        what = f"{named('task', component)}: form_template"
        core = {"prefix": f"{task}.", "image_width": width, "image_height": height}
        with blamed(origin, what):
            source = component.form_template
            if not isinstance(source, str):
                raise PluginBug(f"{origin}: {what} is {type(source).__name__}; expected a str")
            # autoescaped like core's templates
            page = environment().from_string(source).render(**context, **core)
            return valid_unicode(page)

    def _prompt_options(self, task: str) -> PromptOptions:
        cot = self.options.cot.get(task, self.tasks[task].default_cot)
        return PromptOptions(self.options.input_mode, cot, self.options.force_numeric, 0)

    def submit(self, fields: Mapping[str, str], shown_at: float) -> None:
        """Check every field of a posted form and store one answer per task.

        Raises:
            FormError: A field is unknown, missing or invalid, or the scene is not one of the
                session's; nothing is stored.
            PluginBug: A task's read_form() or parse() raised or returned something else than
                it should, naming its plugin; nothing is stored.
        """
        self._check_token(fields)
        ref = self.scene(fields.get("scene", ""))
        if ref is None:  # any scene of the session: the next, or one answered before (back)
            raise FormError("scene: not a scene of this session")
        answers = self._read(fields, ref)
        seconds = max(time.time() - shown_at, 0.0)
        log = AttemptLog(self.run_dir)
        try:
            for task, (value, rule, ms) in answers.items():
                latency = min(ms / 1000, seconds) if ms is not None else seconds
                self._store(ref, task, value, rule, latency, log)
        finally:
            log.close()

    def _read(
        self, fields: Mapping[str, str], ref: SceneRef
    ) -> dict[str, tuple[dict[str, Any], str | None, int | None]]:
        if len(fields) > MAX_FIELDS:
            raise FormError(f"form: more than {MAX_FIELDS} fields")
        by_task: dict[str, dict[str, str]] = {name: {} for name in self.tasks}
        times: dict[str, int | None] = dict.fromkeys(self.tasks)
        for key, value in fields.items():
            if len(value) > MAX_VALUE:
                raise FormError(f"{key[:40]}: longer than {MAX_VALUE} characters")
            task, dot, rest = key.partition(".")
            if key in ("scene", "shown", "token"):
                continue
            if task == "ms" and rest in self.tasks:
                times[rest] = _milliseconds(key, value)
            elif dot and task in self.tasks and rest:
                by_task[task][rest] = value
            else:
                raise FormError(f"{key[:40]}: not a field of this form")
        scene = ref.load()
        out: dict[str, tuple[dict[str, Any], str | None, int | None]] = {}
        for name, component in self.tasks.items():
            assert isinstance(component, AnswersInBrowser)
            origin = self.registry.origin("task", name)
            try:
                answer = form_answer(component, origin, by_task[name], scene)
            except ValueError as exc:
                raise FormError(f"{name}.{exc}") from None
            try:
                options = self._prompt_options(name)
                parsed = parsed_answer(self.tasks[name], origin, json.dumps(answer), scene, options)
            except ParseFailure as exc:
                raise FormError(f"{name}: {exc}") from None
            out[name] = (dict(parsed.value), parsed.rule, times[name])
        return out

    def _store(
        self, ref: SceneRef, task: str, value: dict[str, Any], rule: str | None,
        latency: float, log: AttemptLog,
    ) -> None:  # fmt: skip
        text = json.dumps(value)
        log.append(
            {
                "time": time.time(), "scene_id": ref.scene_id, "task": task,
                "adapter": self.spec, "attempt": 1, "escalation": 0, "outcome": "ok", "text": text,
                "latency": latency, "rule": rule, "error": None,
            }
        )  # fmt: skip
        record = Tally(attempts=1, responses=1, latency=round(latency, 3)).record(
            ref,
            task,
            self.spec,
            status="ok",
            answer=value,
            rule=rule,
            finish_reason="stop",
            input_mode=self.options.input_mode,
            cot=self._prompt_options(task).cot,
        )
        write_answer(self.run_dir, ref.key, record)


def _milliseconds(key: str, value: str) -> int:
    if not (value.isascii() and value.isdigit()) or int(value) > MAX_MS:
        raise FormError(f"{key}: expected whole milliseconds from 0 to {MAX_MS}")
    return int(value)


def form_context(
    task: AnswersInBrowser, origin: str, scene: Any, image: bytes | None
) -> dict[str, Any]:
    """``task.form_context(scene, image)``, checked: a dict of template values named by str,
    none of them one core adds (:data:`RESERVED`).

    Raises:
        PluginBug: The task raised or returned something else, naming ``origin``.
    """
    what = f"{named('task', task)}: form_context()"
    with blamed(origin, what):
        context = task.form_context(scene, image)
    if not isinstance(context, dict) or not all(isinstance(k, str) for k in context):
        raise PluginBug(
            f"{origin}: {what} returned {type(context).__name__}; expected a dict of template "
            "values named by str"
        )
    taken = sorted(set(RESERVED) & set(context))
    if taken:
        raise PluginBug(f"{origin}: {what} returned {taken[0]!r}, a value core sets itself")
    return context


def form_answer(
    task: AnswersInBrowser, origin: str, fields: Mapping[str, str], scene: Any
) -> dict[str, Any]:
    """``task.read_form(fields, scene)``, checked: a dict JSON can hold (the answer's text).
    A ``ValueError`` passes through: it is how a task says which field is wrong.

    Raises:
        ValueError: The task refused a field (its message names it).
        PluginBug: The task raised anything else or returned something else, naming ``origin``.
    """
    what = f"{named('task', task)}: read_form()"
    with blamed(origin, what, passing=(ValueError,)):
        answer = task.read_form(fields, scene)
    try:
        if not isinstance(answer, dict):
            raise TypeError(f"a {type(answer).__name__}")
        json.dumps(answer, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise PluginBug(
            f"{origin}: {what} returned no answer JSON can hold ({exc}); expected a dict in the "
            "task's answer format"
        ) from exc
    return answer


def human_app(session: HumanSession) -> Starlette:
    """The app answering ``session``'s dataset."""

    async def index(request: Request) -> Response:
        asked = request.query_params.get("scene")
        ref = session.next_scene() if asked is None else session.scene(asked)
        if asked is not None and ref is None:
            return error_page(f"scene {asked[:40]!r}: not in this session", 404)
        if ref is None:
            return HTMLResponse(render("human_done.html", session=session))
        scene = ref.load()
        width, height = _image_size(ref.image())
        page = session.page(ref)
        forms = {
            name: Markup(session.form(name, context, width, height))
            for name, context in page.forms.items()
        }
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

    def answer(fields: dict[str, str]) -> str:
        try:
            shown = float(fields.get("shown", ""))
        except ValueError:
            raise FormError("shown: expected the time the page was shown") from None
        if not 0 < shown <= time.time() + 5:
            raise FormError("shown: not a time this page could have been shown")
        session.submit(fields, shown)
        return "/"

    def skip(fields: dict[str, str]) -> str:
        session.skip(fields)
        return "/"

    def undo(fields: dict[str, str]) -> str:
        return f"/?scene={quote(session.undo(fields).scene_id)}"

    async def image(request: Request) -> Response:
        sid = request.path_params["scene_id"]
        ref = session.scene(sid)
        if ref is None:
            return error_page(f"scene {sid!r}: not in this session", 404)
        return Response(ref.image(), media_type="image/png")

    return Starlette(
        routes=[
            Route("/", index),
            Route("/answer", _posted(answer), methods=["POST"]),
            Route("/skip", _posted(skip), methods=["POST"]),
            Route("/undo", _posted(undo), methods=["POST"]),
            Route("/image/{scene_id}", image),
        ],
        middleware=[loopback_only()],
        exception_handlers={PluginBug: plugin_bug_page},  # nothing stored
    )


def _posted(action: Callable[[dict[str, str]], str]) -> Callable[[Request], Any]:
    """The endpoint of a posted form: ``action`` on its fields, then a redirect to the page it
    names; a form it refuses (:class:`FormError`) or one :func:`_fields` refuses is an error
    page."""

    async def endpoint(request: Request) -> Response:
        fields = await _fields(request)
        if isinstance(fields, Response):
            return fields
        try:
            return RedirectResponse(action(fields), status_code=303)
        except FormError as exc:
            return error_page(str(exc))

    return endpoint


async def _fields(request: Request) -> dict[str, str] | Response:
    """The posted form's fields, or the error page of a form too large, malformed or holding
    repeated or file fields."""
    try:
        form = await request.form(max_files=0, max_fields=MAX_FIELDS, max_part_size=MAX_FIELD_BYTES)
    except HTTPException as exc:  # too many or too long fields, a malformed body
        return error_page(f"form: {exc.detail}")
    fields = {k: v for k, v in form.multi_items() if isinstance(v, str)}
    if len(fields) != len(form.multi_items()):
        return error_page("form: repeated or file fields")
    return fields


def _image_size(png: bytes) -> tuple[int, int]:
    with Image.open(io.BytesIO(png)) as img:
        return img.size
