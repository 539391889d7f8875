"""``bpb prompt``: print the exact messages a run would send for one scene and task."""

from __future__ import annotations

from pathlib import Path

import click

from bpb_core.cli.params import PATH, counted, force_numeric_option, input_mode_option


@click.command("prompt")
@click.argument("scene", type=PATH)
@click.option("--task", default="q1", show_default=True, help="The task whose prompt to print.")
@click.option("--data", type=PATH, help="Dataset folder, to give SCENE as an id.")
@input_mode_option
@click.option("--cot/--no-cot", "cot", default=None, help="Chain of thought (default: the task's).")
@force_numeric_option
@counted(
    "--escalation",
    default=0,
    low=0,
    help="The re-ask level (0 first ask; 1, 2 after malformed answers).",
)
def prompt(
    scene: Path,
    task: str,
    data: Path | None,
    input_mode: str,
    cot: bool | None,
    force_numeric: bool,
    escalation: int,
) -> None:
    """Print the messages sent about SCENE (init.json, its folder, or an id with --data);
    images appear as a placeholder with their size and SHA-256, as in the attempts log."""
    from bpb_core.cli.console import load_registry
    from bpb_core.interfaces import PromptOptions
    from bpb_core.model_calls import ImagePart
    from bpb_core.runner.dry_run import describe_image, preview_messages

    registry = load_registry()
    chosen = registry.task(task).default_cot if cot is None else cot
    options = PromptOptions(input_mode, chosen, force_numeric, escalation)  # type: ignore[arg-type]
    for message in preview_messages(scene, task, options, registry, data):
        click.echo(f"--- {message.role} ---")
        for part in message.parts:
            click.echo(describe_image(part) if isinstance(part, ImagePart) else part.text)
