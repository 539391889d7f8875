"""Calls into plugin code, checked: each runs one method a plugin supplies under
:func:`~bpb_core.errors.blamed` and checks what it returns, so a plugin's mistake is one line
naming the plugin (:class:`~bpb_core.errors.PluginBug`, exit 3) instead of a traceback, or an
error blamed on whatever took the value next (a task's ``expected``, an adapter, run.json).

``origin`` is always who supplied the object (a registry entry's origin, or the module of an
object no plugin registers). Every function raises :class:`~bpb_core.errors.PluginBug`, naming
``origin`` and the component, when the plugin code raises or returns something other than what
its docstring says it checks for.
"""

from __future__ import annotations

import json
import random
from typing import TYPE_CHECKING, Any

from bpb_core.capabilities import Bounding, Describing, KnowsFamilies, Preflighting, Pricing
from bpb_core.errors import PluginBug, blamed, named
from bpb_core.interfaces import ParsedAnswer, PromptOptions
from bpb_core.model_calls import CallCeiling, Message, known_cost

if TYPE_CHECKING:
    from bpb_core.capabilities import (
        Estimating,
        Perceiving,
        Predicting,
        PublishesSchema,
        TruthOfMany,
    )
    from bpb_core.interfaces import SceneFamily, Simulator, Task


def prediction(family: Predicting, origin: str, name: str, scene: Any, rng: random.Random) -> Any:
    """``family.predict(name, scene, rng)``, checked: an instance of the family's
    ``truth_model`` (what takes it next, a task's ``expected``, would be blamed for anything
    else)."""
    what = f"{family_label(family)}: predict({name!r})"
    with blamed(origin, what):
        truth = family.predict(name, scene, rng)
    return _checked_model(family, origin, what, truth, "truth_model")


def offered_predictors(family: Predicting, origin: str) -> tuple[str, ...]:
    """``family.predictors``, checked: a tuple (or list) of names (a str would be taken letter
    by letter, offering ``baseline:s``)."""
    what = f"{family_label(family)}: predictors"
    with blamed(origin, what):
        names = family.predictors
    if isinstance(names, tuple | list) and all(isinstance(name, str) for name in names):
        return tuple(names)
    raise PluginBug(f"{origin}: {what} is {names!r:.80}; expected a tuple of names (str)")


def simulated_truth(
    family: SceneFamily,
    origin: str,
    scene: Any,
    simulator: Simulator,
    *,
    horizon: float | None = None,
    stability: bool = False,
) -> Any:
    """``family.ground_truth(scene, simulator, horizon, stability=...)``, checked as
    :func:`prediction` is (``bpb simulate``, ``baseline:oracle`` and ``baseline:vision`` answer
    from it)."""
    what = f"{family_label(family)}: ground_truth()"
    with blamed(origin, what):
        truth = family.ground_truth(scene, simulator, horizon, stability=stability)
    return _checked_model(family, origin, what, truth, "truth_model")


def simulated_truths(
    family: TruthOfMany, origin: str, scenes: list[Any], simulator: Simulator, horizon: float | None
) -> list[Any]:
    """``family.ground_truths(scenes, simulator, horizon)``, checked: a list of one instance of
    the family's ``truth_model`` per scene (each is paired with its scene file by position)."""
    what = f"{family_label(family)}: ground_truths()"
    with blamed(origin, what):
        truths = family.ground_truths(scenes, simulator, horizon)
    if not isinstance(truths, list) or len(truths) != len(scenes):
        got = f"a list of {len(truths)}" if isinstance(truths, list) else type(truths).__name__
        raise PluginBug(
            f"{origin}: {what} returned {got} for {len(scenes)} scenes; expected a list with "
            "one ground truth per scene"
        )
    return [_checked_model(family, origin, what, truth, "truth_model") for truth in truths]


def perception(
    family: Perceiving, origin: str, image: bytes, prompt: str
) -> tuple[Any, str | None]:
    """``family.perceive(image, prompt)``, checked: an instance of the family's ``scene_model``
    (its ``ground_truth()`` runs on it next and would be blamed for anything else) and
    ``None``; or, when it raises ``ValueError`` (how it says the image cannot be read), ``None``
    and why."""
    what = f"{family_label(family)}: perceive()"
    with blamed(origin, what):
        try:
            scene = family.perceive(image, prompt)
        except ValueError as exc:
            return None, str(exc) or type(exc).__name__
    return _checked_model(family, origin, what, scene, "scene_model"), None


def loaded_config(family: SceneFamily, origin: str, source: Any) -> Any:
    """``family.load_config(source)``, checked: an instance of the family's ``config_model``
    (the manifest records it and the family's other hooks take it). A
    :class:`~bpb_core.errors.BadInput` naming the file or field passes through."""
    what = f"{family_label(family)}: load_config()"
    with blamed(origin, what):
        config = family.load_config(source)
    return _checked_model(family, origin, what, config, "config_model")


def simulator_named(family: SceneFamily, origin: str, config: Any) -> str:
    """``family.simulator_name(config)``, checked: a simulator's spec (a non-empty str: its name,
    optionally with options, ``pymunk:dt=0.0005``), which is parsed and looked up in the
    registry next and recorded in the manifest."""
    what = f"{family_label(family)}: simulator_name()"
    with blamed(origin, what):
        name = family.simulator_name(config)
    if isinstance(name, str) and name:
        return name
    raise returned(origin, what, f"{name!r:.80}", "a simulator's name (str)")


def prompt_messages(
    task: Task, origin: str, scene: Any, image: bytes | None, options: PromptOptions
) -> tuple[Message, ...]:
    """``task.messages(scene, image, options)``, checked: a sequence of
    :class:`~bpb_core.model_calls.Message` (an adapter that choked on anything else would be
    blamed for it)."""
    what = f"{named('task', task)}: messages()"
    with blamed(origin, what):
        messages = task.messages(scene, image, options)
    if isinstance(messages, tuple | list) and all(isinstance(m, Message) for m in messages):
        return tuple(messages)
    got = type(messages).__name__
    if isinstance(messages, tuple | list):
        got = f"a {got} of {', '.join(sorted({type(m).__name__ for m in messages}))}"
    raise returned(origin, what, got, "a tuple of bpb_core.Message")


def parsed_answer(
    task: Task, origin: str, text: str, scene: Any, options: PromptOptions
) -> ParsedAnswer:
    """``task.parse(text, scene, options)``, checked: a :class:`ParsedAnswer` holding a dict
    (the answer file and the scorer take its ``value``). A :class:`ParseFailure` passes
    through: it is how a task says the reply holds no answer."""
    what = f"{named('task', task)}: parse()"
    with blamed(origin, what):
        parsed = task.parse(text, scene, options)
    if isinstance(parsed, ParsedAnswer) and isinstance(parsed.value, dict):
        return parsed
    got = type(parsed).__name__
    if isinstance(parsed, ParsedAnswer):
        got = f"a ParsedAnswer whose value is {type(parsed.value).__name__}"
    raise returned(origin, what, got, "a bpb_core.ParsedAnswer with a dict value")


def published_schema(task: PublishesSchema, origin: str) -> dict[str, Any]:
    """``task.answer_schema()``, checked: a dict (an adapter that choked on anything else, with
    ``--structured-output``, would be blamed for it)."""
    what = f"{named('task', task)}: answer_schema()"
    with blamed(origin, what):
        schema = task.answer_schema()
    if isinstance(schema, dict):
        return schema
    raise returned(origin, what, type(schema).__name__, "a dict (a JSON Schema)")


def returned(origin: str, what: str, got: str, expected: str) -> PluginBug:
    """The one-line error for plugin code (``what``, supplied by ``origin``) that returned the
    wrong thing: ``<origin>: <what> returned <got>; expected <expected>``."""
    return PluginBug(f"{origin}: {what} returned {got}; expected {expected}")


def family_label(family: object) -> str:
    """``scene family 'billiards'``: how one-line plugin errors name a family."""
    return named("scene family", family)


def family_model(family: object, attribute: str) -> type | None:
    """The family's model named ``attribute`` (``truth_model``, ``config_model``), or ``None``
    when it declares none: then what its hooks return is not checked against one."""
    model = getattr(family, attribute, None)
    return model if isinstance(model, type) else None


def _checked_model(family: object, origin: str, what: str, value: Any, attribute: str) -> Any:
    """``value`` if it is an instance of the family's model named ``attribute`` (e.g. its
    ``truth_model``: what takes it next, a task's ``expected``, would fail on anything else and
    be blamed for it)."""
    model = family_model(family, attribute)
    if model is None or isinstance(value, model):
        return value
    expected = f"{model.__name__} (the family's {attribute})"
    raise returned(origin, what, type(value).__name__, expected)


def described_settings(adapter: object, origin: str) -> dict[str, Any] | None:
    """The adapter's :meth:`Describing.settings` as run.json stores them (``None`` without
    them), checked: a dict that JSON can hold (a tuple comes back a list, as a resume reads it)."""
    if not isinstance(adapter, Describing):
        return None
    what = f"{named('adapter', adapter)}: settings()"
    with blamed(origin, what):
        settings = adapter.settings()
    return json_values(origin, what, settings, "settings run.json")


def json_values(origin: str, what: str, value: object, held_as: str) -> dict[str, Any]:
    """``value``, returned by ``what`` (``scene family 'x': physics()``), as a JSON file holds
    it, if it is a dict that JSON can hold (a tuple comes back a list, a key 1 the key "1", as a
    reader of the file finds them); ``held_as`` is what the message calls it and the file it is
    stored in (``what dataset.json``). Else the :class:`PluginBug` says why."""
    try:
        if not isinstance(value, dict):
            raise TypeError(f"a {type(value).__name__}, not a dict")
        held: dict[str, Any] = json.loads(json.dumps(value, allow_nan=False))
    except TypeError as exc:
        why = str(exc)
    except ValueError as exc:  # the wording of json's own message differs between versions
        why = str(exc) if str(exc).startswith("Circular") else "a NaN or infinity"
    else:
        return held
    raise PluginBug(
        f"{origin}: {what} returned {held_as} cannot hold ({why}); expected a dict of JSON values"
    )


def preflight_problem(adapter: object, origin: str) -> str | None:
    """The adapter's :meth:`Preflighting.preflight` (``None`` without it), checked: ``None`` or
    a str (anything else would be shown to the user as what to fix, or break the run before
    its first call naming no plugin)."""
    if not isinstance(adapter, Preflighting):
        return None
    what = f"{named('adapter', adapter)}: preflight()"
    with blamed(origin, what):
        problem = adapter.preflight()
    return _checked_line(origin, what, problem)


def answer_refusal(adapter: object, origin: str, family: SceneFamily) -> str | None:
    """The adapter's :meth:`KnowsFamilies.cannot_answer` for ``family`` (``None`` without it),
    checked as :func:`preflight_problem` is."""
    if not isinstance(adapter, KnowsFamilies):
        return None
    what = f"{named('adapter', adapter)}: cannot_answer({getattr(family, 'name', '?')!r})"
    with blamed(origin, what):
        why = adapter.cannot_answer(family)
    return _checked_line(origin, what, why)


def price_known(adapter: object, origin: str) -> bool | None:
    """The adapter's :attr:`Pricing.priced` (``None`` without it), checked: a bool (``--max-cost``
    refuses the adapter when it is false, and would take any other value's truth for it)."""
    what = f"{named('adapter', adapter)}: priced"
    with blamed(origin, what):  # before Python 3.12, isinstance reads the property too
        if not isinstance(adapter, Pricing):
            return None
        priced = adapter.priced
    if isinstance(priced, bool):
        return priced
    raise PluginBug(f"{origin}: {what} is {priced!r:.80}; expected a bool")


def estimated_input(
    adapter: Estimating, origin: str, messages: tuple[Message, ...]
) -> tuple[int, float | None]:
    """``adapter.estimate(messages)``, checked: input tokens (an int, at least 0) and their cost
    in USD (a finite number, at least 0, or ``None``), which ``bpb run --dry-run`` adds up."""
    what = f"{named('adapter', adapter)}: estimate()"
    with blamed(origin, what):
        estimate = adapter.estimate(messages)
    if isinstance(estimate, tuple | list) and len(estimate) == 2:
        tokens, cost = estimate
        if _count(tokens) and (cost is None or known_cost(cost) is not None):
            return tokens, None if cost is None else float(cost)
    expected = "(input tokens, cost): an int at least 0 and a finite float at least 0 or None"
    raise returned(origin, what, f"{estimate!r:.80}", expected)


def call_ceiling(
    adapter: object, origin: str, messages: tuple[Message, ...], max_tokens: int | None
) -> CallCeiling | None:
    """``adapter.ceiling(messages, max_tokens)`` (``None`` without :class:`Bounding`), checked:
    a :class:`CallCeiling` of counts at least 0 and finite costs at least 0, or ``None``."""
    if not isinstance(adapter, Bounding):
        return None
    what = f"{named('adapter', adapter)}: ceiling()"
    with blamed(origin, what):
        ceiling = adapter.ceiling(messages, max_tokens)
    if ceiling is None:
        return None
    if isinstance(ceiling, CallCeiling) and _count(ceiling.input_tokens):
        out = ceiling.output_tokens
        prices = (ceiling.input_cost, ceiling.output_price)
        if (out is None or _count(out)) and all(known_cost(p) is not None for p in prices):
            return ceiling
    expected = "a CallCeiling (counts >= 0, finite costs >= 0) or None"
    raise returned(origin, what, f"{ceiling!r:.80}", expected)


def _checked_line(origin: str, what: str, line: object) -> str | None:
    """``line`` if it is ``None`` or a str (one line shown to the user)."""
    if line is None or isinstance(line, str):
        return line
    raise returned(origin, what, type(line).__name__, "None or a str")


def _count(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0
