"""``bpb human`` (people answer a dataset in the browser) and ``bpb view`` (browse runs): both
serve a local web app on 127.0.0.1 (see :mod:`bpb_core.web`)."""

from __future__ import annotations

from pathlib import Path

import click

from bpb_core.cli import console
from bpb_core.cli.console import load_registry, stderr

PORT_HELP = "Port on 127.0.0.1 (the apps never listen on other interfaces)."
PORTS = click.IntRange(0, 65535)


@click.command("human")
@click.option("--data", required=True, type=console.PATH, help="Dataset folder.")
@click.option("--out", required=True, type=console.PATH, help="Run folder.")
@click.option("--name", default="anonymous", show_default=True, help="Who answers (human:NAME).")
@click.option("--tasks", help="Comma-separated tasks (default: the family's default tasks).")
@console.horizons_option
@console.limit_option
@click.option("--seed", default=0, show_default=True, help="Seed of the scene order.")
@click.option("--port", default=8765, show_default=True, type=PORTS, help=PORT_HELP)
def human(
    data: Path,
    out: Path,
    name: str,
    tasks: str | None,
    horizons: str | None,
    limit: int | None,
    seed: int,
    port: int,
) -> None:
    """Answer a dataset's questions in the browser; saved as a normal run (human:NAME),
    resumable, scenes in a seeded order."""
    from bpb_core.run_folder import make_run_folder
    from bpb_core.runner.manifest import run_lock
    from bpb_core.runner.options import RunOptions
    from bpb_core.web import listen, require_web, serve, url

    require_web()
    from bpb_core.web.human import HumanSession, human_app

    chosen = tuple(console.csv_list(tasks, "--tasks"))
    options = RunOptions(tasks=chosen, horizons=console.horizons(horizons), limit=limit)
    sock = listen(port)  # a port in use is refused before the run folder is made
    make_run_folder(out)
    with run_lock(out):  # as bpb run's: a second session (or a run) on the folder is refused
        session = HumanSession(data, out, name, load_registry(), options, seed)
        stderr().print(f"bpb human: open {url(sock)} (Ctrl-C stops; answers are kept)")
        serve(human_app(session), sock)


@click.command("view")
@click.argument("run_dirs", nargs=-1, required=True, type=console.PATH)
@click.option("--port", default=8766, show_default=True, type=PORTS, help=PORT_HELP)
def view(run_dirs: tuple[Path, ...], port: int) -> None:
    """Browse runs pair by pair: image, exact prompt, every attempt, verdicts."""
    from bpb_core.web import listen, require_web, serve, url

    require_web()
    from bpb_core.web.viewer import Viewer, viewer_app

    sock = listen(port)
    viewer = Viewer.load(list(run_dirs), load_registry())
    stderr().print(f"bpb view: open {url(sock)} (Ctrl-C stops)")
    serve(viewer_app(viewer), sock)
