"""``bpb run`` and ``bpb prompt``: ask models the benchmark's questions (a thin wrapper over
bpb_core.runner), and print the exact messages a run would send for one scene and task;
``bpb human``: people answer them in a local web app on 127.0.0.1 (see :mod:`bpb_core.web`).

Exit codes: 0 every (scene, task) got a reply (``ok``, ``parse_error``, ``refused``, ``cut``,
``empty``), or a ``--pilot`` done;
1 the run finished with ``api_error`` pairs or pairs left unsent by ``--max-cost`` (re-run the
same command to resume); 2 bad input, or an adapter stopped by an error no retry can fix (an
unknown model, an invalid parameter, a spent quota, a refused key, a provider that cannot be
reached: that adapter stops at once, the others of a sweep go on; fix it and re-run the same
command to resume).

Run files (``bpb run --config paper.toml``) and ``--model-arg`` give one option set per adapter.

A run file lists adapters, each with its own options::

    [defaults]                      # optional: applies to every adapter below
    timeout = 300

    [[adapter]]
    spec = "litellm:gpt-5.4"        # required
    label = "effort=high"           # optional: names the option set (default: made from args)
    api_base = "http://127.0.0.1:8000/v1"
    timeout = 600                   # seconds per call
    concurrency = 4                 # calls in flight
    rpm = 60                        # requests per minute
    tpm = 200000                    # tokens per minute (input plus output)
    max_cost = 20                   # USD this adapter's folder may spend, all sessions
    args = {reasoning_effort = "high", max_tokens = 16000}
    headers = {"anthropic-beta" = "..."}
    price = {input = 2.5e-6, output = 1.5e-5, cache_read = 2.5e-7}

``args`` go to the provider unchanged (``thinking = {type = "enabled", budget_tokens = 8000}``),
``headers`` as extra HTTP headers.

What ``bpb run`` prints: the live progress rows (one per adapter and task), the table of what a
dry run would send (from :mod:`bpb_core.runner.dry_run`), and the summary of scores at the end
(from :mod:`bpb_core.results`).
"""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib
from collections import Counter
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress as RichBar, TextColumn
from rich.table import Column, Table

from bpb_core.cli import console
from bpb_core.cli.console import (
    PATH,
    PORT_HELP,
    PORTS,
    FiniteFloat,
    Name,
    counted,
    csv_list,
    force_numeric_option,
    horizons,
    horizons_option,
    input_mode_option,
    limit_option,
    load_registry,
    pct,
    positive,
    print_fitted,
    stderr,
    stdout,
)
from bpb_core.errors import BadInput, BpbError
from bpb_core.model_calls import AdapterOptions, check_api_base, known_cost, non_finite

if TYPE_CHECKING:
    import pandas as pd
    from rich.progress import TaskID

    from bpb_core.dataset.reader import DataFolder
    from bpb_core.registry import Registry
    from bpb_core.runner.dry_run import DryRun
    from bpb_core.runner.options import ProgressEvent, RunOptions, RunResult

_RUN_KEYS = {
    "timeout": (int, float),
    "concurrency": (int,),
    "rpm": (int, float),
    "tpm": (int, float),
    "max_cost": (int, float),
}
_KEYS = {"spec", "label", "api_base", "args", "headers", "price", *_RUN_KEYS}


@dataclass(frozen=True)
class AdapterPlan:
    """One adapter of a run with its own options.

    Attributes:
        spec: ``name:model``.
        options: What the adapter factory receives (api_base, model arguments, prices, label).
        run: Per-adapter overrides of the run options (``timeout``, ``concurrency``, ``rpm``,
            ``tpm``, ``max_cost``: a cap of its own within the command's ``--max-cost``).
    """

    spec: str
    options: AdapterOptions
    run: dict[str, Any] = field(default_factory=dict)


def _value(text: str) -> Any:
    try:
        return json.loads(text)
    except ValueError:
        return text


def model_args(items: Iterable[str]) -> dict[str, Any]:
    """``--model-arg KEY=VALUE`` items as a dict; values are JSON when they parse (``16000``,
    ``true``, ``{"budget_tokens": 8000}``), else strings; ``a.b=1`` nests as ``{"a": {"b": 1}}``.

    Raises:
        BadInput: An item without ``=`` or with an empty key.
    """
    out: dict[str, Any] = {}
    for item in items:
        key, sep, text = item.partition("=")
        if not sep or not key.strip() or any(not part for part in key.split(".")):
            raise BadInput(f"--model-arg {item!r}: expected KEY=VALUE, e.g. reasoning_effort=high")
        *path, last = key.strip().split(".")
        target = out
        for part in path:
            inner = target.setdefault(part, {})
            if not isinstance(inner, dict):
                raise BadInput(f"--model-arg {item!r}: {part} is already a value")
            target = inner
        value = _value(text)
        bad = non_finite(value, key.strip())
        if bad is not None:
            raise BadInput(
                f"--model-arg {item!r}: {bad[0]} must be a finite number, got {bad[1]!r} "
                "(model arguments are sent as JSON, which has no NaN or infinity)"
            )
        target[last] = value
    return out


def _check(where: str, table: Mapping[str, Any], spec_required: bool) -> None:
    unknown = sorted(set(table) - _KEYS)
    if unknown:
        raise BadInput(f"{where}: unknown key {unknown[0]!r}; known: {', '.join(sorted(_KEYS))}")
    if spec_required and not isinstance(table.get("spec"), str):
        raise BadInput(f"{where}.spec: required, a string like 'litellm:gpt-5.4'")
    for key, types in _RUN_KEYS.items():
        value = table.get(key)
        if value is not None and (not isinstance(value, types) or isinstance(value, bool)):
            raise BadInput(f"{where}.{key}: expected a number, got {value!r}")
        if value is not None and not 0 < value < math.inf:  # nan and inf too (TOML has both)
            raise BadInput(f"{where}.{key}: must be a positive finite number, got {value!r}")
    if "label" in table and not isinstance(table["label"], str):
        raise BadInput(f"{where}.label: expected a string, got {table['label']!r}")
    if "api_base" in table:  # else litellm names no provider for an api_base of 3
        check_api_base(table["api_base"], f"{where}.api_base")
    for key in ("args", "headers", "price"):
        if key in table and not isinstance(table[key], dict):
            raise BadInput(f"{where}.{key}: expected a table")
    for name, value in table.get("headers", {}).items():  # else sent as "{'a': 1}"
        if not isinstance(value, (str, int, float)) or isinstance(value, bool):
            raise BadInput(f"{where}.headers.{name}: expected a string, got {value!r}")
    if "price" in table:
        check_price(f"{where}.price", table["price"])
    bad = non_finite(table.get("args"), f"{where}.args")
    if bad is not None:  # TOML has nan and inf; the JSON a provider is sent has neither
        raise BadInput(f"{bad[0]}: must be a finite number, got {bad[1]!r}")


def check_price(where: str, price: Mapping[str, Any]) -> None:
    """Every value of one model's price override must be a finite number >= 0 (USD per token):
    a NaN price would make every cost NaN, and ``--max-cost`` never stop (NaN >= cap is false).

    Raises:
        BadInput: ``"<where>.<field>: must be a finite number >= 0, got nan"``.
    """
    for key, value in price.items():
        if known_cost(value) is None:
            raise BadInput(f"{where}.{key}: must be a finite number >= 0, got {value!r}")


def check_price_table(source: str, table: Any) -> dict[str, dict[str, float]]:
    """A ``--prices`` table: ``{"model": {"input": .., "output": ..}}``, every price a finite
    number >= 0.

    Raises:
        BadInput: One line naming ``source`` and the model and field at fault.
    """
    if not isinstance(table, dict):
        raise BadInput(f"{source}: expected a JSON object of models, got {type(table).__name__}")
    for model, price in table.items():
        if not isinstance(price, dict):
            raise BadInput(f'{source}: {model}: expected an object like {{"input": ..}}')
        check_price(f"{source}: {model}", price)
    return table


def _plan(
    table: Mapping[str, Any], base: AdapterOptions, cli_args: Mapping[str, Any]
) -> AdapterPlan:
    args = {**table.get("args", {}), **cli_args}
    if table.get("headers"):
        args["extra_headers"] = {str(k): str(v) for k, v in table["headers"].items()}
    spec = str(table["spec"])
    prices = dict(base.prices)
    if "price" in table:
        prices[spec.partition(":")[2]] = dict(table["price"])
    options = dataclasses.replace(
        base,
        api_base=table.get("api_base", base.api_base),
        model_args=args,
        label=table.get("label"),
        prices=prices,
    )
    return AdapterPlan(spec, options, {k: table[k] for k in _RUN_KEYS if k in table})


def read_run_file(
    path: Path, base: AdapterOptions, cli_args: Mapping[str, Any]
) -> list[AdapterPlan]:
    """The adapters of a run file; ``cli_args`` (``--model-arg``) override each one's args.

    Raises:
        BadInput: The file is unreadable, not TOML, or a field is wrong (named in the message).
    """
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise BadInput(f"{path}: not a readable TOML run file ({exc})") from None
    unknown = sorted(set(data) - {"defaults", "adapter"})
    if unknown:
        raise BadInput(f"{path}: unknown table {unknown[0]!r}; expected [defaults], [[adapter]]")
    defaults = data.get("defaults", {})
    if not isinstance(defaults, dict):
        raise BadInput(f"{path}: defaults: expected a [defaults] table, got {defaults!r}")
    _check(f"{path}: defaults", defaults, spec_required=False)
    adapters = data.get("adapter")
    if not isinstance(adapters, list) or not adapters:
        raise BadInput(f"{path}: no [[adapter]] entries")
    plans = []
    for number, table in enumerate(adapters, 1):
        if not isinstance(table, dict):
            raise BadInput(
                f"{path}: adapter {number}: expected an [[adapter]] table, got {table!r}"
            )
        merged = {**defaults, **table}
        _check(f"{path}: adapter {number}", merged, spec_required=True)
        plans.append(_plan(merged, base, cli_args))
    return plans


@dataclass(frozen=True)
class Prepared:
    """An adapter built and checked before the first call of the run, and who supplied it."""

    name: str
    adapter: Any
    plan: AdapterPlan
    origin: str


def prepare(registry: Any, plans: list[AdapterPlan], *, check: bool = True) -> list[Prepared]:
    """Build every adapter and run its preflight (unless ``check`` is false: a dry run needs no
    key), all before any call is sent.

    Raises:
        BadInput: A preflight failed (a key missing, an unknown provider, a module missing), or
            two adapters would share a run folder name.
    """
    from bpb_core.runner.run import adapter_origin, check_adapter, run_name

    ready: list[Prepared] = []
    for plan in plans:
        adapter = registry.adapter(plan.spec, plan.options)
        origin = adapter_origin(registry, plan.spec, adapter)
        if check:
            check_adapter(plan.spec, adapter, origin)
        ready.append(Prepared(run_name(plan.spec, adapter), adapter, plan, origin))
    names = [p.name for p in ready]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        labels = {p.plan.options.label for p in ready if p.name == twice[0]}
        if len(labels) > 1:  # labelled apart, yet one name: the adapter has no option sets
            raise BadInput(
                f"--adapter {twice[0]}: given twice; this adapter does not name its runs by "
                "label (it has no option sets), so both would write one run folder: give it once"
            )
        raise BadInput(f"--adapter {twice[0]}: given twice with the same options; add a label")
    return ready


def refuse_unbounded(ready: list[Prepared], max_tokens: int | None) -> None:
    """A hard cap reserves each call's worst case: refuse a capped adapter that has a price
    but knows no output limit for its calls (no ``--max-tokens``, none in its args, none in its
    model's information).

    Raises:
        BadInput: One line naming the adapter and the way out.
        PluginBug: An adapter's ``ceiling()`` raised or returned something else.
    """
    from bpb_core.plugin_calls import call_ceiling
    from bpb_core.runner.budget import unbounded

    for item in ready:
        ceiling = call_ceiling(item.adapter, item.origin, (), max_tokens)
        if ceiling is not None and ceiling.output_cost is None:
            raise BadInput(unbounded(item.name))


def refuse_unpriced(ready: list[Prepared]) -> None:
    """``--max-cost`` cannot cap what it cannot price: refuse adapters without a price.

    Raises:
        BadInput: Names every adapter without a price and the ways out.
        PluginBug: An adapter's ``priced`` raised or is no bool, naming its plugin.
    """
    from bpb_core.plugin_calls import price_known

    unpriced = [p.name for p in ready if price_known(p.adapter, p.origin) is False]
    if unpriced:
        raise BadInput(
            f"--max-cost: no price known for {', '.join(unpriced)}; give one (--prices, or "
            "price = {...} in the run file) or pass --allow-unpriced to let them run uncounted"
        )


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
    """A plan per adapter and per run-file entry, with --api-base, --prices, --alias and
    --model-arg checked (--api-base first: no adapter is built, no call sent)."""
    api_base, prices = kw["api_base"], kw["prices"]
    if api_base is not None:
        check_api_base(api_base, "--api-base")
    price_table: dict[str, dict[str, float]] = {}
    if prices is not None:
        try:
            loaded = json.loads(prices.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise BadInput(f"{prices}: --prices: not a JSON price table ({exc})") from None
        price_table = check_price_table(f"{prices}: --prices", loaded)
    alias_table = {}
    for item in kw["aliases"]:
        name, sep, target = item.partition("=")
        if not sep or not name or not target:
            raise BadInput(f"--alias {item!r}: expected NAME=LITELLM_MODEL")
        alias_table[name] = target
    base = AdapterOptions(
        api_base=api_base, seed=kw["seed"], prices=price_table, aliases=alias_table
    )
    cli_args = model_args(kw["model_args"])
    plans = [AdapterPlan(spec, replace(base, model_args=dict(cli_args))) for spec in adapters]
    if kw["config"] is not None:
        plans += read_run_file(kw["config"], base, cli_args)
    return plans


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
        show_dry_run(data, out, ready, options, registry)
        return
    from bpb_core.runner import run_eval, slug
    from bpb_core.runner.budget import command_budget
    from bpb_core.runner.run import check_simulator_for

    for item in ready:  # before any adapter's first call
        check_simulator_for(data, item.name, item.adapter, registry)
    shared = command_budget(options.max_cost, [out / slug(item.name) for item in ready])
    results = []
    columns = (BarColumn(), MofNCompleteColumn(), TextColumn("{task.fields[stats]}"))
    with RichBar(TextColumn("{task.description}"), *columns, console=stderr()) as bar:
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
                    pilot=kw["pilot"],
                )
            )
            if results[-1].stopped == "interrupted":  # Ctrl-C / SIGTERM stops every adapter
                break
    if kw["pilot"] is not None:
        show_dry_run(data, out, ready, options, registry, pilot=True)
    raise click.exceptions.Exit(_finish(results, registry, data, summary=kw["pilot"] is None))


def _finish(
    results: list[RunResult], registry: Registry, data: DataFolder, *, summary: bool = True
) -> int:
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


FAILED = ("parse_error", "refused", "cut", "empty", "api_error")
"""Final statuses other than ``ok`` of a pair that was sent."""
_SHORT = {"parse_error": "parse", "api_error": "api"}
_ALWAYS = ("parse_error", "api_error")  # shown even at 0; the rest only once they happen


@dataclass
class _Row:
    task_id: TaskID
    counts: Counter[str] = field(default_factory=Counter)  # by event kind and final status
    cost: float | None = 0.0

    def fields(self) -> dict[str, Any]:
        n, cost = self.counts, "$?" if self.cost is None else f"${self.cost:.4f}"
        failed = sum(n[s] for s in FAILED)
        kinds = ", ".join(f"{_SHORT.get(s, s)} {n[s]}" for s in FAILED if n[s] or s in _ALWAYS)
        text = f"ok {n['ok']} failed {failed} ({kinds}) retrying {n['retry']} "
        text += f"tok {n['tokens']:,} {cost}"
        if n["skipped"]:
            text += f" | {n['skipped']} done before"
        if n["not_sent"]:
            text += f" | {n['not_sent']} not sent"
        return {"stats": text}


class RichProgress:
    """Draws :class:`~bpb_core.runner.options.ProgressEvent` s as rich progress bars."""

    def __init__(self, bar: RichBar) -> None:
        self._bar = bar
        self._rows: dict[tuple[str, str], _Row] = {}

    def update(self, event: ProgressEvent) -> None:
        """Apply one event to its row (a warning is printed above the bars)."""
        if event.kind == "warning":
            text = escape(f"{event.adapter}: {event.reason}")
            self._bar.console.print(f"[yellow]warning:[/] {text}")
            return
        key = (event.adapter, event.task)
        if key not in self._rows:
            name = escape(f"{event.adapter} {event.task}")
            self._rows[key] = _Row(self._bar.add_task(name, total=0, stats=""))
        row = self._rows[key]
        n = row.counts
        if event.kind == "done":
            n[event.status or "ok"] += 1
            n["tokens"] += event.tokens
            if row.cost is not None:
                row.cost = None if event.cost is None else row.cost + event.cost
        else:  # planned, skipped (done before), retry
            n[event.kind] += event.count
        finished = n["ok"] + sum(n[s] for s in FAILED) + n["not_sent"]
        self._bar.update(row.task_id, total=n["planned"], completed=finished, **row.fields())


def show_dry_run(
    data: DataFolder,
    out: Path,
    ready: list[Prepared],
    options: RunOptions,
    registry: Registry,
    *,
    pilot: bool = False,
) -> None:
    """Print, per adapter and task and in total, the calls a run would send, those already
    done, the estimated input tokens and USD, the output USD typical and at the cap, and the
    basis of each figure (nothing is sent). After ``--pilot`` it is the projection from the
    pilot's real usage."""
    from bpb_core.runner import slug
    from bpb_core.runner.dry_run import dry_run, plus

    title = "bpb run --pilot: projection from the pilot's real usage (not sent)"
    table = Table(
        Column("adapter", no_wrap=True, min_width=max(len(item.name) for item in ready)),
        "task", "calls", "done before", "input tokens", "input USD",
        "output USD typical", "output USD at cap", "projected USD",
        title=title if pilot else "bpb run --dry-run (nothing sent)",
    )  # fmt: skip
    sums: list[float | None] = [0.0, 0.0, 0.0, 0.0]
    notes = []
    for item in ready:
        plan = dry_run(data, out / slug(item.name), options, registry, item.adapter, item.origin)
        for task in options.tasks:
            row = plan.task(task)
            money = [row.input_cost, row.typical_output_cost, row.cap_output_cost, row.projected]
            sums = [plus(a, b) for a, b in zip(sums, money, strict=True)]
            table.add_row(
                escape(item.name), task, str(row.calls), str(row.done),
                f"{row.input_tokens:,}", *(_usd(v) for v in money),
            )  # fmt: skip
        notes.append(_basis(item.name, plan, options.tasks, out / slug(item.name)))
    table.add_row("total", "", "", "", "", *(_usd(v) for v in sums), end_section=True)
    stdout().print(table)
    for line in notes:
        stdout().print(escape(line), highlight=False, soft_wrap=True)


def _usd(value: float | None) -> str:
    return "no price" if value is None else f"${value:,.4f}"


def _basis(name: str, plan: DryRun, tasks: Iterable[str], folder: Path) -> str:
    """Where one adapter's figures come from: its count and prices, the output cap, and the
    typical output (the pairs already done, or the assumption before any)."""
    from bpb_core.runner.dry_run import TYPICAL_OUTPUT

    priced = plan.basis or "input ~ characters / 4 (the adapter cannot price a call)"
    seen = {t: plan.task(t).seen for t in tasks if plan.task(t).seen}
    if seen:
        each = ", ".join(f"{t} {n} at {plan.task(t).typical_tokens:,.0f}" for t, n in seen.items())
        typical = f"typical and projected: the real usage of pairs done in {folder} ({each} "
        typical += "output tokens per pair, re-asks included)"
    else:
        typical = f"typical: an assumed {TYPICAL_OUTPUT:,} output tokens per call, or the cap "
        typical += "if lower (no replies yet; --pilot N measures them)"
    return f"basis {name}: {priced}; {typical}"


def show_spending(results: Iterable[RunResult]) -> None:
    """Print, per capped run, what was spent (all sessions), reserved and left, and the pairs
    the cap kept from being sent."""
    for result in results:
        budget = result.budget
        if budget.get("cap") is None and budget.get("command_cap") is None:
            continue
        # one line: spent, reserved and left under each cap, and the pairs the cap kept
        parts = [f"{result.adapter}: spent ${budget['spent']:.4f} (all sessions)"]
        if budget.get("cap") is not None:
            parts.append(f"its cap ${budget['cap']:.4f}, ${budget['left']:.4f} left")
        if budget.get("command_cap") is not None:
            parts.append(
                f"--max-cost ${budget['command_cap']:.4f} over the command: "
                f"${budget['command_spent']:.4f} spent, ${budget['command_left']:.4f} left"
            )
        parts.append(f"reserved ${budget['reserved']:.4f}")
        kept = budget.get("kept_by_cap") or []
        if kept:
            shown = ", ".join(kept[:5]) + (", ..." if len(kept) > 5 else "")
            parts.append(f"the cap kept {len(kept)} pairs from being sent ({shown})")
        stderr().print(escape("; ".join(parts)), highlight=False)


_NOT_SCORES = (
    "run", "adapter", "model", "baseline", "expected", "epochs", "completeness", "worst_cell",
)  # fmt: skip


def show_summary(
    run_dirs: list[Path], registry: Registry, folders: Iterable[DataFolder] = ()
) -> None:
    """Write ``scores.csv`` into each run folder and print the leaderboard summary
    (``folders``: the runs' datasets, already read)."""
    from bpb_core.results.frames import write_scores

    try:
        frame = write_scores(run_dirs, registry, folders)
    except BpbError as exc:
        stderr().print(f"[yellow]warning:[/] could not score the run: {exc}")
        return
    if frame is None or frame.empty:
        return
    _print_table(frame)
    _print_footnote(frame, registry)
    for run, line in frame.attrs.get("warnings", []):
        stderr().print(f"[yellow]{escape(run)}: {escape(line)}[/]", highlight=False)
    parents = sorted({str(d.parent) for d in run_dirs})
    where = " ".join(parents) if parents else "RUN_DIR"
    stderr().print(
        f"next: bpb report {where} --out {parents[0] if parents else '.'}/report "
        "(charts, failure gallery, HTML)",
        highlight=False,
    )


def _print_footnote(frame: pd.DataFrame, registry: Registry) -> None:
    """What the columns mean, and what each offline adapter family in the table answers (its
    summary), so a reader knows what the floors and the ceiling are."""
    from bpb_core.results.tables import DEFAULT_MIN_COMPLETE

    lines = [
        "complete: share of the run's (scene, task) pairs answered. A task's score is its mean "
        "over the answered pairs; in brackets the strict score, where an unanswered pair counts "
        f"as wrong (the paper's rule). left out: tasks under {DEFAULT_MIN_COMPLETE:.0%} "
        "answered, not scored."
    ]
    families = {str(a).partition(":")[0] for a in frame["adapter"]}
    for name, entry in registry.entries("adapter").items():
        info = entry.info
        if name in families and getattr(info, "offline", False) and info.summary:
            lines.append(f"{name}: {info.summary}")
    for line in lines:
        stdout().print(escape(line), style="dim", highlight=False)


def _print_table(frame: pd.DataFrame) -> None:
    """Answered-only scores and completeness first, the strict score beside each."""
    names = [
        c for c in frame.columns
        if c not in _NOT_SCORES and c != "short" and not c.endswith("_answered")
    ]  # fmt: skip
    rows = []
    for _, row in frame.iterrows():
        cells = [pct(row["completeness"])]
        for name in names:
            answered, strict = row[f"{name}_answered"], row[name]
            if not math.isnan(float(answered)):
                cells.append(f"{pct(answered)} ({pct(strict)})")
            else:  # too incomplete, or not asked (a suite with a task the run lacks)
                cells.append("left out" if row["short"] else "–")
        cells.append(escape(str(row["short"])) or "–")
        rows.append((Name(str(row["adapter"])), cells))
    title = "bpb run: scores (answered only; strict in brackets)"
    print_fitted(stdout(), title, ["adapter", "complete", *names, "left out"], rows)


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


@click.command("human")
@click.option("--data", required=True, type=PATH, help="Dataset folder.")
@click.option("--out", required=True, type=PATH, help="Run folder.")
@click.option("--name", default="anonymous", show_default=True, help="Who answers (human:NAME).")
@click.option("--tasks", help="Comma-separated tasks (default: the family's default tasks).")
@horizons_option
@limit_option
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

    chosen = tuple(csv_list(tasks, "--tasks"))
    options = RunOptions(tasks=chosen, horizons=console.horizons(horizons), limit=limit)
    sock = listen(port)  # a port in use is refused before the run folder is made
    make_run_folder(out)
    with run_lock(out):  # as bpb run's: a second session (or a run) on the folder is refused
        session = HumanSession(data, out, name, load_registry(), options, seed)
        stderr().print(f"bpb human: open {url(sock)} (Ctrl-C stops; answers are kept)")
        serve(human_app(session), sock)
