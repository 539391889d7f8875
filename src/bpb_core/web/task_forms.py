"""The browser form hooks of a task (:class:`~bpb_core.capabilities.AnswersInBrowser`), called
checked: each runs under :func:`~bpb_core.errors.blamed` and its value is checked, so a task's
mistake is one line naming its plugin (:class:`~bpb_core.errors.PluginBug`, shown by ``bpb
human`` as an error page) instead of a bare 500, or an answer stored that is no answer.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

from bpb_core.capabilities import AnswersInBrowser
from bpb_core.errors import PluginBug, blamed
from bpb_core.web.templating import render_string

RESERVED = ("prefix", "image_width", "image_height")
"""Template values core adds to a task's :meth:`form_context`."""


def form_context(
    task: AnswersInBrowser, origin: str, scene: Any, image: bytes | None
) -> dict[str, Any]:
    """``task.form_context(scene, image)``, checked: a dict of template values named by str,
    none of them one core adds (:data:`RESERVED`).

    Raises:
        PluginBug: The task raised or returned something else, naming ``origin``.
    """
    what = f"{_task(task)}: form_context()"
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


def form_html(task: AnswersInBrowser, origin: str, context: dict[str, Any], **core: Any) -> str:
    """The task's ``form_template`` rendered with ``context`` and core's values (``core``).

    Raises:
        PluginBug: The template is no str or does not render, naming ``origin``.
    """
    what = f"{_task(task)}: form_template"
    with blamed(origin, what):
        source = task.form_template
        if not isinstance(source, str):
            raise PluginBug(f"{origin}: {what} is {type(source).__name__}; expected a str")
        return render_string(source, **context, **core)


def form_answer(
    task: AnswersInBrowser, origin: str, fields: Mapping[str, str], scene: Any
) -> dict[str, Any]:
    """``task.read_form(fields, scene)``, checked: a dict JSON can hold (the answer's text).
    A ``ValueError`` passes through: it is how a task says which field is wrong.

    Raises:
        ValueError: The task refused a field (its message names it).
        PluginBug: The task raised anything else or returned something else, naming ``origin``.
    """
    what = f"{_task(task)}: read_form()"
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


def _task(task: object) -> str:
    return f"task {getattr(task, 'name', type(task).__name__)!r}"
