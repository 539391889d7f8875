"""``bpb plugins`` and ``bpb list``."""

from __future__ import annotations

import json
from typing import Any

import click

from bpb_core.cli.console import load_registry, stdout
from bpb_core.registry import AdapterInfo, Kind, Registered

LIST_KINDS: dict[str, Kind] = {
    "tasks": "task",
    "adapters": "adapter",
    "simulators": "simulator",
    "scorers": "scorer",
    "scene-families": "scene_family",
    "suites": "suite",
    "diagnostics": "diagnostic",
    "references": "reference",
}


def _row(entry: Registered) -> dict[str, Any]:
    row: dict[str, Any] = {
        "name": entry.info.name,
        "kind": entry.info.kind,
        "distribution": entry.distribution,
        "version": entry.version,
        "plugin": entry.plugin,
        "summary": entry.info.summary,
    }
    info = entry.info
    if isinstance(info, AdapterInfo):
        row["models"] = list(info.models)
        row["offline"] = info.offline
    for name in ("family", "task", "tasks", "weights", "default"):
        if hasattr(info, name):
            value = getattr(info, name)
            row[name] = dict(value) if name == "weights" else value
    return row


@click.command("plugins")
@click.option("--json", "as_json", is_flag=True, help="Print JSON for scripts.")
def plugins(as_json: bool) -> None:
    """List every registered component with its plugin, distribution and version."""
    registry = load_registry()
    rows = [_row(entry) for entry in registry]
    if as_json:
        click.echo(json.dumps(rows, indent=2))
        return
    from rich.table import Table

    table = Table("kind", "name", "distribution", "version", "summary", title="bpb plugins")
    for row in rows:
        table.add_row(row["kind"], row["name"], row["distribution"], row["version"], row["summary"])
    stdout().print(table)


@click.command("list")
@click.argument("what", type=click.Choice(sorted(LIST_KINDS)))
def list_components(what: str) -> None:
    """List the names of one kind of component: tasks, adapters, simulators, scorers,
    scene families, suites or diagnostics."""
    registry = load_registry()
    kind = LIST_KINDS[what]
    for entry in registry.entries(kind).values():
        names = [(entry.info.name, entry.info.summary)]
        if isinstance(entry.info, AdapterInfo) and entry.info.models:
            names = [(f"{entry.info.name}:{m}", entry.info.summary) for m in entry.info.models]
        if isinstance(entry.info, AdapterInfo) and entry.info.catalog is not None:
            rows = entry.info.catalog()()
            names += [(f"{entry.info.name}:{model}", text) for model, text in rows]
        for name, text in names:
            click.echo(f"{name}\t{text}")
