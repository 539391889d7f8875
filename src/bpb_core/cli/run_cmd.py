"""``bpb run``: ask models the benchmark's questions (a thin wrapper over bpb_core.runner).

Exit codes: 0 every (scene, task) got a reply (``ok``, ``parse_error``, ``refused``, ``cut``,
``empty``), or a ``--pilot`` done;
1 the run finished with ``api_error`` pairs or pairs left unsent by ``--max-cost`` (re-run the
same command to resume); 2 bad input, or an adapter stopped by an error no retry can fix (an
unknown model, an invalid parameter, a spent quota, a refused key, a provider that cannot be
reached: that adapter stops at once, the others of a sweep go on; fix it and re-run the same
command to resume).
"""

from __future__ import annotations

import json
from dataclasses import fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click
from rich.markup import escape

from bpb_core.cli.console import load_registry, stderr
from bpb_core.cli.params import (
    PATH,
    FiniteFloat,
    counted,
    csv_list,
    force_numeric_option,
    horizons,
    horizons_option,
    input_mode_option,
    limit_option,
    positive,
)
from bpb_core.errors import BadInput

if TYPE_CHECKING:
    from bpb_core.cli.run_file import AdapterPlan, Prepared
    from bpb_core.dataset.reader import DataFolder
    from bpb_core.model_calls import AdapterOptions
    from bpb_core.registry import Registry
    from bpb_core.runner.options import RunOptions, RunResult

DEFAULT_OUT = "runs"
QUICK_PER_HORIZON = 10


def _cot(tasks: list[str], enable: bool | None, per_task: str | None) -> dict[str, bool]:
    if per_task is not None:
        chosen = set(csv_list(per_task, "--cot")) if per_task.strip().lower() != "none" else set()
        unknown = chosen - set(tasks)
        if unknown:
            raise BadInput(f"--cot: {sorted(unknown)} not among --tasks {tasks}")
        return {t: t in chosen for t in tasks}
    return {} if enable is None else {t: enable for t in tasks}


def _plans(kw: dict[str, Any], adapters: list[str]) -> list[AdapterPlan]:
    from bpb_core.cli.run_file import AdapterPlan, model_args, read_run_file

    base = _adapter_options(kw["api_base"], kw["seed"], kw["prices"], kw["aliases"])
    cli_args = model_args(kw["model_args"])
    plans = [AdapterPlan(spec, replace(base, model_args=dict(cli_args))) for spec in adapters]
    if kw["config"] is not None:
        plans += read_run_file(kw["config"], base, cli_args)
    return plans


def _adapter_options(
    api_base: str | None, seed: int, prices: Path | None, aliases: tuple[str, ...]
) -> AdapterOptions:
    from bpb_core.cli.run_file import check_price_table
    from bpb_core.model_calls import AdapterOptions, check_api_base

    if api_base is not None:  # checked before the rest: no adapter is built, no call sent
        check_api_base(api_base, "--api-base")
    price_table: dict[str, dict[str, float]] = {}
    if prices is not None:
        try:
            loaded = json.loads(prices.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise BadInput(f"{prices}: --prices: not a JSON price table ({exc})") from None
        price_table = check_price_table(f"{prices}: --prices", loaded)
    alias_table = {}
    for item in aliases:
        name, sep, target = item.partition("=")
        if not sep or not name or not target:
            raise BadInput(f"--alias {item!r}: expected NAME=LITELLM_MODEL")
        alias_table[name] = target
    return AdapterOptions(api_base=api_base, seed=seed, prices=price_table, aliases=alias_table)


def _offline_adapters(registry: Registry, data: DataFolder) -> list[str]:
    """Every model of every offline adapter that can answer the dataset's scene family (and
    whose simulator, if it runs one, is installed)."""
    from bpb_core.plugin_calls import answer_refusal
    from bpb_core.runner.run import adapter_origin, check_simulator_for

    family = data.family
    chosen = []
    for spec in registry.offline_specs():
        adapter = registry.adapter(spec)
        if answer_refusal(adapter, adapter_origin(registry, spec, adapter), family) is not None:
            continue
        try:
            check_simulator_for(data, spec, adapter, registry)
        except BadInput as exc:  # e.g. the oracle, on a dataset whose simulator is gone
            stderr().print(
                f"[yellow]note:[/] left out: {escape(str(exc))}", highlight=False, soft_wrap=True
            )
            continue
        chosen.append(spec)
    if not chosen:
        raise BadInput(f"--adapter: none given and no offline adapter answers {family.name} scenes")
    return chosen


def _check_names(registry: Registry, tasks: list[str], adapters: list[str]) -> None:
    from bpb_core.model_calls import split_spec

    for task in tasks:
        registry.get("task", task)
    for spec in adapters:
        registry.get("adapter", split_spec(spec)[0])


def _data(data: Path | None, out: Path, seed: int, registry: Registry) -> Path:
    if data is not None:
        from bpb_core.dataset.reader import resolve_data

        return resolve_data(data)
    quick = out / "data"
    if (quick / "dataset.json").exists():
        return quick
    from bpb_core.dataset import generate_dataset

    stderr().print(
        f"no --data: generating a small dataset ({QUICK_PER_HORIZON} scenes per horizon, "
        f"seed {seed}) in {quick}"
    )
    return generate_dataset(quick, QUICK_PER_HORIZON, [1, 2, 3, 4, 5], seed, registry=registry)


def _note_unpriced(ready: list[Prepared], prices: Path) -> None:
    """A ``--prices`` table that prices none of an adapter's calls is said now, with the table's
    keys: a key that is not the model's litellm name (``my-vlm`` for ``openai/my-vlm``) would
    else show the live cost as ``$?`` all run."""
    from bpb_core.plugin_calls import price_known

    for item in ready:
        if price_known(item.adapter, item.origin) is False:
            keys = ", ".join(sorted(item.plan.options.prices)) or "none"
            stderr().print(
                f"[yellow]note:[/] {escape(str(prices))}: --prices: no price for "
                f"{escape(item.name)} (its keys: {escape(keys)}); key it by the model's litellm "
                "name, or its cost is unknown ($?)",
                highlight=False, soft_wrap=True,
            )  # fmt: skip


@click.command("run")
@click.option(
    "--data", type=PATH, help="Dataset folder (default: a small generated one in OUT/data)."
)
@click.option(
    "--tasks",
    help="Comma-separated tasks [default: the default tasks of the dataset's scene family].",
)
@click.option(
    "--adapter",
    "adapters",
    multiple=True,
    help="NAME:MODEL, repeatable (default: every offline adapter's models, e.g. the baselines).",
)
@horizons_option
@limit_option
@click.option("--scenes", help="Only these scene ids, comma-separated (h1_0003,h2_0010).")
@click.option(
    "--sample", type=click.IntRange(min=1), help="A random sample of N scenes (seeded by --seed)."
)
@counted(
    "--epochs",
    default=1,
    help="Ask every (scene, task) K times (repeated samples, stored and scored apart).",
)
@click.option(
    "--temperature",
    type=FiniteFloat(min=0),
    default=0.0,
    show_default=True,
    help="Sampling temperature (the paper: 0).",
)
@counted("--concurrency", default=8, help="Calls in flight at once, per adapter.")
@click.option("--rpm", type=positive(), help="Requests per minute cap.")
@click.option("--tpm", type=positive(), help="Tokens per minute cap (in + out).")
@click.option(
    "--out",
    type=PATH,
    default=Path(DEFAULT_OUT),
    show_default=True,
    help="Writes OUT/<adapter slug>/ per adapter.",
)
@click.option(
    "--enable-cot/--no-cot",
    "enable_cot",
    default=None,
    help="Chain of thought for every task (default: each task's own default).",
)
@click.option(
    "--cot",
    "cot_tasks",
    help="Tasks with chain of thought, comma-separated (or 'none'); overrides --enable-cot.",
)
@click.option("--max-tokens", type=click.IntRange(min=1), help="Output token cap per call.")
@click.option(
    "--timeout",
    type=positive(),
    default=120.0,
    show_default=True,
    help="Seconds per call (grows on retries).",
)
@force_numeric_option
@click.option(
    "--structured-output",
    is_flag=True,
    help="Offer each task's answer JSON Schema to providers that accept one (not the paper's).",
)
@input_mode_option
@click.option("--api-base", help="Base URL of an OpenAI-compatible or provider endpoint.")
@click.option(
    "--dry-run", is_flag=True, help="Count calls, estimate tokens and USD (a range); send nothing."
)
@click.option(
    "--pilot",
    type=click.IntRange(min=1),
    help="Send N pairs per adapter, print the projection from their real usage and stop "
    "(a later run resumes from them).",
)
@click.option(
    "--max-cost",
    type=positive(),
    help="Most USD the command may spend, over all its adapters and sessions (each call's "
    "worst case is reserved before it is sent).",
)
@click.option(
    "--seed",
    type=int,
    default=0,
    show_default=True,
    help="Seed of the call order, of --sample and of adapters with randomness.",
)
@counted(
    "--retries",
    default=6,
    low=0,
    help="Retries after 429/5xx/timeouts/connection errors (5 connection failures in a row, "
    "or 30 s of them, stop the adapter).",
)
@counted("--reasks", default=2, low=0, help="Escalating re-asks after a malformed answer.")
@click.option(
    "--prices",
    type=click.Path(path_type=Path, dir_okay=False),
    help='JSON {"model": {"input": usd_per_token, "output": usd_per_token}}.',
)
@click.option("--alias", "aliases", multiple=True, help="NAME=LITELLM_MODEL, repeatable.")
@click.option(
    "--model-arg",
    "model_args",
    multiple=True,
    help="KEY=VALUE passed to the provider, repeatable: reasoning_effort=high, max_tokens=16000, "
    "thinking.budget_tokens=8000, extra_headers.NAME=VALUE (VALUE parsed as JSON if it can be).",
)
@click.option(
    "--allow-unpriced",
    is_flag=True,
    help="Let --max-cost run adapters without a price (their calls are not counted).",
)
@click.option(
    "--config",
    type=click.Path(path_type=Path, dir_okay=False),
    help="TOML run file listing adapters, each with its own options (see docs/providers.md).",
)
def run(**kw: Any) -> None:
    """Ask each adapter every task about every selected scene; resume by re-running."""
    from bpb_core.cli.run_file import prepare, refuse_unbounded, refuse_unpriced
    from bpb_core.dataset.reader import open_folder
    from bpb_core.layout import check_writable_folder
    from bpb_core.runner.options import RetryPolicy, RunOptions

    check_writable_folder(kw["out"], "--out")  # before any work: a file or unwritable path
    registry = load_registry()
    tasks = csv_list(kw["tasks"], "--tasks")
    _check_names(registry, tasks, list(kw["adapters"]))
    out: Path = kw["out"]
    plans = _plans(kw, list(kw["adapters"]))
    _check_names(registry, [], [p.spec for p in plans])
    check = not kw["dry_run"]  # a dry run sends nothing, so it needs no key
    ready = prepare(registry, plans, check=check) if plans else []  # preflight: before any call
    data = open_folder(_data(kw["data"], out, kw["seed"], registry), registry)  # read once
    tasks = tasks or registry.tasks_for(data.family.name, default_only=True)
    if not ready:
        ready = prepare(registry, _plans(kw, _offline_adapters(registry, data)), check=check)
    if kw["prices"] is not None:
        _note_unpriced(ready, kw["prices"])
    capped = [p for p in ready if kw["max_cost"] is not None or "max_cost" in p.plan.run]
    if capped and not kw["dry_run"]:
        if not kw["allow_unpriced"]:
            refuse_unpriced(capped)
        refuse_unbounded(capped, kw["max_tokens"])
    given = {f.name: kw[f.name] for f in fields(RunOptions) if f.name in kw}  # as click parsed
    given.update(
        tasks=tuple(tasks),
        horizons=horizons(kw["horizons"]),
        scenes=tuple(csv_list(kw["scenes"], "--scenes")) if kw["scenes"] is not None else None,
        cot=_cot(tasks, kw["enable_cot"], kw["cot_tasks"]),
        retry=RetryPolicy(max_retries=kw["retries"], max_reasks=kw["reasks"]),
    )
    options = RunOptions(**given)
    if kw["dry_run"]:
        from bpb_core.cli.run_output import show_dry_run

        show_dry_run(data, out, ready, options, registry)
        return
    from bpb_core.runner.run import check_simulator_for

    for item in ready:  # before any adapter's first call
        check_simulator_for(data, item.name, item.adapter, registry)
    results = _run_all(data, out, ready, options, registry, kw["pilot"])
    if kw["pilot"] is not None:
        from bpb_core.cli.run_output import show_dry_run

        show_dry_run(data, out, ready, options, registry, pilot=True)
    raise click.exceptions.Exit(_finish(results, registry, data, summary=kw["pilot"] is None))


def _run_all(
    data: DataFolder,
    out: Path,
    ready: list[Prepared],
    options: RunOptions,
    registry: Registry,
    pilot: int | None,
) -> list[RunResult]:
    from bpb_core.cli.run_output import RichProgress, make_bar
    from bpb_core.runner import run_eval, slug
    from bpb_core.runner.budget import command_budget

    shared = command_budget(options.max_cost, [out / slug(item.name) for item in ready])
    results = []
    with make_bar() as bar:
        display = RichProgress(bar)
        for item in ready:  # --max-cost is the command's; a run file's max_cost the adapter's
            results.append(
                run_eval(
                    data,
                    item.adapter,
                    out / slug(item.name),
                    replace(options, max_cost=None, **item.plan.run),
                    registry=registry,
                    progress=display,
                    spec=item.name,
                    flag="--adapter",
                    shared_budget=shared,
                    pilot=pilot,
                )
            )
            if results[-1].stopped == "interrupted":  # Ctrl-C / SIGTERM stops every adapter
                break
    return results


def _finish(
    results: list[RunResult], registry: Registry, data: DataFolder, *, summary: bool = True
) -> int:
    from bpb_core.cli.run_output import show_spending, show_summary

    if summary:
        show_summary([r.run_dir for r in results], registry, [data])
    show_spending(results)
    code = 0
    for result in results:
        if result.stopped == "setup":
            stderr().print(
                f"[red]error:[/] {escape(result.adapter)}: stopped, {escape(result.error or '')}; "
                f"{result.not_sent} pairs not sent: fix it, then re-run the same command to resume",
                soft_wrap=True,  # one line, however long the provider's message
            )
            code = 2
        elif result.api_errors or result.not_sent:
            why = {"max-cost": "max cost reached; ", "interrupted": "interrupted; "}.get(
                result.stopped or "", ""
            )
            how = "re-run the same command to resume"
            if result.stopped == "max-cost":  # the cap counts earlier sessions: a re-run sends none
                how = "re-run with a higher --max-cost (it counts every session) to send them"
            stderr().print(
                f"[yellow]{escape(result.adapter)}:[/] {why}{result.api_errors} api errors, "
                f"{result.not_sent} not sent; {how}"
            )
            code = max(code, 1)
    return code
