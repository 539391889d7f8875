"""The Jinja2 environment of the web apps: core's templates from this package, every value
autoescaped, and the tasks' form templates rendered in the same environment."""

from __future__ import annotations

import functools
from typing import Any

import jinja2

from bpb_core.model_calls import valid_unicode


@functools.cache
def environment() -> jinja2.Environment:
    """Templates of ``bpb_core/web/templates`` with autoescaping on (also for strings)."""
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


def render_string(source: str, **context: Any) -> str:
    """A plugin's template source rendered with ``context`` (autoescaped like core's)."""
    return valid_unicode(environment().from_string(source).render(**context))
