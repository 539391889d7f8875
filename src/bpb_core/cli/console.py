"""The rich console the CLI writes to, and how registry warnings reach the user.

Emoji codes are off: adapter specs are ``name:model``, and a line such as ``echo:x: 2 api
errors`` must not print ``echo❌ 2 api errors`` (rich reads ``:x:`` as an emoji code).
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from rich.console import Console

    from bpb_core.registry import Registry


PIPE_WIDTH = 140  # tables piped to a file or a log are not squeezed into 80 columns


@functools.cache
def stdout() -> Console:
    """Console on standard output (140 columns when piped, unless COLUMNS says otherwise)."""
    import os
    import sys

    from rich.console import Console

    piped = not sys.stdout.isatty() and "COLUMNS" not in os.environ
    return Console(width=PIPE_WIDTH if piped else None, emoji=False)


@functools.cache
def stderr() -> Console:
    """Console on standard error (progress, warnings)."""
    from rich.console import Console

    return Console(stderr=True, emoji=False)


def load_registry() -> Registry:
    """Build the registry and show each plugin warning on stderr as one line."""
    from bpb_core.registry import make_registry

    registry = make_registry(warn=False)
    for line in registry.warnings:
        stderr().print(f"[yellow]warning:[/] {line}", highlight=False, soft_wrap=True)
    return registry
