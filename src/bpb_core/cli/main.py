"""Entry point of the ``bpb`` command.

Subcommands live in their own modules and are imported only when invoked, so ``bpb --help`` does
not pay for pydantic, numpy or litellm. Errors become one line on stderr and an exit code:
0 ok, 1 finished with errors, 2 usage or bad input, 3 internal error.
"""

from __future__ import annotations

import importlib
import os
import sys
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, TextIO

import click

from bpb_core.version import __version__

# name -> (module in bpb_core.cli, attribute, one-line help); the help is here so listing needs
# no import.
COMMANDS: dict[str, tuple[str, str, str]] = {
    "plugins": ("plugins_cmd", "plugins", "List installed plugins and versions."),
    "list": ("plugins_cmd", "list_components", "List tasks, adapters, ..."),
    "bench": ("bench", "bench", "Benchmarks (speed against error)."),
    "run": ("run_cmd", "run", "Ask models the benchmark's questions (resumable)."),
    "generate": ("dataset_cmd", "generate", "Generate a dataset (scenes, images)."),
    "export": ("dataset_cmd", "export", "Export a dataset (Hugging Face Parquet)."),
    "report": ("report_cmd", "report", "Score and compare runs; charts and HTML."),
    "prompt": ("run_cmd", "prompt", "Print the exact messages sent for a scene."),
    "human": ("run_cmd", "human", "Answer the questions in the browser (a run)."),
    "view": ("report_cmd", "view", "Browse runs in the browser, pair by pair."),
    "simulate": ("simulate_cmd", "simulate", "Simulate scenes; print final.json lines."),
}


class LazyGroup(click.Group):
    """A group whose subcommands are imported on first use."""

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted(COMMANDS)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        entry = COMMANDS.get(cmd_name)
        if entry is None:
            return None
        module, attribute, _ = entry
        command = getattr(importlib.import_module(f"bpb_core.cli.{module}"), attribute)
        assert isinstance(command, click.Command)
        return command

    def format_commands(self, ctx: click.Context, formatter: click.HelpFormatter) -> None:
        rows = [(name, COMMANDS[name][2]) for name in self.list_commands(ctx)]
        with formatter.section("Commands"):
            formatter.write_dl(rows)


@click.group(cls=LazyGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="bpb")
def cli() -> None:
    """bpb: generate scenes with simulated ground truth,
    ask multimodal LLMs what happens, score them and report where they fail."""


@contextmanager
def notes_on_stderr() -> Iterator[None]:
    """Show each :class:`~bpb_core.errors.Notice` (a plugin's word before slow work) as one
    ``note:`` line on stderr in the block, in this process and the workers it forks; other
    warnings as Python shows them. The caller's warning settings are restored after."""
    with warnings.catch_warnings():
        shown = warnings.showwarning

        def show(
            message: Warning | str,
            category: type[Warning],
            filename: str,
            lineno: int,
            file: TextIO | None = None,
            line: str | None = None,
        ) -> None:
            from bpb_core.errors import Notice

            if not issubclass(category, Notice):
                shown(message, category, filename, lineno, file, line)
                return
            from rich.markup import escape

            from bpb_core.cli.console import stderr

            text = f"[yellow]note:[/] {escape(str(message))}"
            stderr().print(text, highlight=False, soft_wrap=True)

        warnings.showwarning = show
        yield


def main(argv: list[str] | None = None) -> None:
    """Run the CLI and exit with bpb's exit codes; the caller's process is left as it was."""
    with notes_on_stderr():
        code = _run(argv)
    sys.exit(code if isinstance(code, int) else 0)


def _run(argv: list[str] | None) -> Any:
    try:
        return cli.main(args=argv, prog_name="bpb", standalone_mode=False)
    except click.exceptions.Abort as exc:
        from bpb_core.errors import Interrupted

        cause = exc.__cause__  # what the interrupted command left where, when it says
        told = isinstance(cause, Interrupted) and str(cause)
        click.echo(f"aborted; {cause}" if told else "aborted", err=True)
        return 130
    except click.exceptions.NoArgsIsHelpError as exc:  # bare ``bpb``: the help, not an error
        click.echo(exc.ctx.get_help() if exc.ctx is not None else exc.format_message())
        return 0
    except click.UsageError as exc:  # one line, like every other bad input
        where = f" (see {exc.ctx.command_path} --help)" if exc.ctx is not None else ""
        click.echo(f"error: {exc.format_message()}{where}", err=True)
        return 2
    except click.ClickException as exc:
        exc.show()
        return exc.exit_code
    except click.exceptions.Exit as exc:
        return exc.exit_code
    except Exception as exc:  # every failure leaves as one line and an exit code
        return _report_error(exc)


def _report_error(exc: BaseException) -> int:
    from bpb_core.errors import BpbError, PluginBug

    if os.environ.get("BPB_DEBUG"):
        import traceback

        traceback.print_exception(exc)
    if isinstance(exc, PluginBug):  # the plugin's author wants the traceback
        click.echo(f"error: {exc} (set BPB_DEBUG=1 for a traceback)", err=True)
        return exc.exit_code
    if isinstance(exc, BpbError):
        click.echo(f"error: {exc}", err=True)
        return exc.exit_code
    click.echo(
        f"internal error: {type(exc).__name__}: {exc} (set BPB_DEBUG=1 for a traceback)", err=True
    )
    return 3


if __name__ == "__main__":
    main()
