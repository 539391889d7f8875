"""Run files (``bpb run --config paper.toml``) and ``--model-arg``: one option set per adapter.

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
"""

from __future__ import annotations

import dataclasses
import json
import math
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bpb_core.errors import BadInput
from bpb_core.model_calls import AdapterOptions, known_cost, non_finite

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
    for key in ("api_base", "label"):  # else litellm names no provider for an api_base of 3
        if key in table and not isinstance(table[key], str):
            raise BadInput(f"{where}.{key}: expected a string, got {table[key]!r}")
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
