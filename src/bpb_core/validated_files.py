"""Reading pydantic-validated files and turning validation errors into one-line messages.

Every file bpb reads (scenes, ground truth, manifests, configs) goes through here, so every user
mistake reads the same way: ``<file>: <field.path[index]>: what is wrong``.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError

from bpb_core.errors import BadInput

M = TypeVar("M", bound=BaseModel)


def describe_validation_error(exc: ValidationError) -> str:
    """The first problem of a pydantic error as ``field.path: message`` on one line."""
    errors = exc.errors()
    first: dict[str, Any] = dict(errors[0])
    message = str(first.get("msg", "invalid")).removeprefix("Value error, ")
    where = ""
    for part in first.get("loc", ()):  # ("items", 2, "pos") -> items[2].pos
        where += f"[{part}]" if isinstance(part, int) else (f".{part}" if where else str(part))
    more = len(errors) - 1
    suffix = f" (and {more} more problem{'s' if more > 1 else ''})" if more else ""
    text = f"{where}: {message}" if where else message
    return " ".join(text.split()) + suffix


def read_model(path: Path, model: type[M], data: bytes | None = None) -> M:
    """Read and validate a JSON file; ``data``: its bytes, already read (a pipe such as
    ``<(...)`` or ``/dev/stdin`` can be read only once). Raises :class:`BadInput`:
    ``"<file>: cannot read: ..."`` or ``"<file>: <field>: problem"``."""
    try:
        return model.model_validate_json(read_bytes(path) if data is None else data)
    except ValidationError as exc:
        raise BadInput(f"{path}: {describe_validation_error(exc)}") from None


def read_bytes(path: Path) -> bytes:
    """The bytes of the file ``path``; raises :class:`BadInput`: ``"<file>: cannot read: ..."``."""
    try:
        return path.read_bytes()
    except OSError as exc:
        raise BadInput(f"{path}: cannot read: {exc.strerror or exc}") from None


def validate_mapping(model: type[M], data: Mapping[str, Any], source: str) -> M:
    """Validate already-parsed ``data`` (a TOML or JSON config) read from ``source``; raises
    :class:`BadInput`: ``"<source>: <field>: problem"``."""
    try:
        return model.model_validate(dict(data))
    except ValidationError as exc:
        raise BadInput(f"{source}: {describe_validation_error(exc)}") from None
