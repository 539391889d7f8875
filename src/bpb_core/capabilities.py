"""Optional capabilities of plugins: what a plugin may offer beyond its interface
(:mod:`bpb_core.interfaces`). Core checks each with ``isinstance`` and does without when it is
missing; each protocol's docstring says what uses it.

- A scene family: :class:`Calibrating`, :class:`Tallying`, :class:`DrawingStats`,
  :class:`Predicting`, :class:`Perceiving`, :class:`BoundsPerception`, :class:`Picturing`,
  :class:`Comparing`, :class:`CountsEvents`, :class:`TruthOfMany`, :class:`DescribesDataset`.
- A simulator: :class:`ExpectsWork`, :class:`RunsMany`.
- An adapter: :class:`KnowsFamilies`, :class:`UsesRegistry`, :class:`NeedsSimulator` (offline
  ones), :class:`Preflighting`, :class:`Describing`, :class:`Pricing`, :class:`Estimating`,
  :class:`Bounding`.
- A task: :class:`AnswersInBrowser`, :class:`PublishesSchema`.
- A scorer: :class:`ExplainsErrors`, :class:`DrawsOverlay`, :class:`ReportsMetrics`.
- A ground truth: :class:`ExplainsInstability`.
"""

from __future__ import annotations

import random
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

# typing_extensions' Protocol reads members as Python 3.12's does (inspect.getattr_static): on
# 3.11 typing's isinstance() ran a plugin's properties (hasattr), so one that raised escaped the
# check itself as a traceback, before bpb could read it under blamed() and name the plugin
from typing_extensions import Protocol, runtime_checkable

if TYPE_CHECKING:
    import pandas as pd

    from bpb_core.interfaces import GroundTruth, SceneFamily, Simulator
    from bpb_core.model_calls import CallCeiling, Message
    from bpb_core.picture import ScenePicture
    from bpb_core.registry import Registry


@runtime_checkable
class ExpectsWork(Protocol):
    """A simulator told how many scenes the command will make before it makes the first, so
    that a one-off cost (compiling a kernel) is paid only when the whole command needs it."""

    def expect_scenes(self, count: int) -> None: ...


@runtime_checkable
class Calibrating(Protocol):
    """A family whose sampling can be tuned to a target (``bpb generate --calibrate``)."""

    def calibrate_horizon(self, config: Any, simulator: Simulator, horizon: float) -> Any:
        """Calibrate one horizon (runs in a worker process; return a picklable value)."""

    def apply_calibration(
        self, config: Any, results: Mapping[float, Any]
    ) -> tuple[Any, dict[str, Any]]:
        """The config updated with the per-horizon results, and the manifest's record."""


class HorizonTally(Protocol):
    """Running per-horizon counts a family keeps while scenes arrive."""

    def add(self, row: Mapping[str, object]) -> None:
        """Count one kept scene (its ``index.csv`` cells)."""

    def summary(self) -> dict[str, Any]:
        """Fields added to the horizon's entry of the manifest's ``summary``."""


@runtime_checkable
class Tallying(Protocol):
    """A family that summarises each horizon in the manifest."""

    def new_tally(self, config: Any, horizon: float) -> HorizonTally:
        """An empty tally for ``horizon``."""


@runtime_checkable
class DrawingStats(Protocol):
    """A family that draws figures of the whole dataset into ``stats/``."""

    def write_stats(
        self, root: Path, config: Any, tallies: Mapping[float, HorizonTally]
    ) -> list[str]:
        """Write the figures under ``root`` and return their paths relative to it."""


@runtime_checkable
class Predicting(Protocol):
    """A family that offers reference predictions (the ``baseline`` adapter's models).

    Attributes:
        predictors: Names it knows besides ``oracle`` (which every family has: its own
            ground truth).
    """

    predictors: tuple[str, ...]

    def predict(self, name: str, scene: Any, rng: random.Random) -> GroundTruth:
        """What predictor ``name`` expects to happen in ``scene``; raises ``KeyError``."""


@runtime_checkable
class Perceiving(Protocol):
    """A family that can read a scene back from exactly what a model is given: the input image
    and the prompt text (``baseline:vision`` runs its own simulator on what it reads, which
    separates seeing from reasoning)."""

    def perceive(self, image: bytes, prompt: str) -> Any:
        """The scene (of the family's scene model) read from ``image`` and ``prompt``; raises
        ``ValueError`` saying in one line what could not be read."""

    def perception_error(self, perceived: Any, scene: Any) -> dict[str, float]:
        """How far ``perceived`` is from the true ``scene``: named numbers, stored with each
        answer (``metadata``) and summarised per horizon by the report."""


@runtime_checkable
class BoundsPerception(Protocol):
    """A :class:`Perceiving` family that can say what even a perfect reader of an image could
    get right: the true scene as the image resolves it (e.g. rounded to its pixel grid),
    simulated, against the ground truth. ``baseline:vision`` stores it with its perception error,
    so the report shows the image's own ceiling beside what was read."""

    def perception_ceiling(
        self, image: bytes, prompt: str, scene: Any, simulator: Simulator
    ) -> dict[str, bool]:
        """Named yes/no measures (which answers survive the image's resolution), stored with
        each answer and shown as shares per horizon by the report; raises ``ValueError`` as
        ``perceive`` does."""


@runtime_checkable
class Picturing(Protocol):
    """A family that can draw a scene for the report's failure gallery."""

    def picture(self, dataset: Path, folder: Path, scene: Any) -> ScenePicture:
        """The scene drawn as an RGB image with its coordinate mapping."""


@runtime_checkable
class Comparing(Protocol):
    """A family whose simulators can be compared on speed and error (``bpb bench sim``).

    Core runs every contestant on the same scenes, times it and hands each outcome to
    :meth:`compare` with the reference's outcome; tables, plot and docs come from core.

    Attributes:
        bench_contestants: Simulators compared by default, each ``name`` or
            ``name:key=value,...`` (options as ``bpb simulate`` takes them).
        bench_reference: The simulator (same form) whose outcomes count as the truth.
        bench_description: One sentence on the scenes :meth:`bench_scenes` draws.
        bench_measures: One sentence on what :meth:`compare`'s numbers mean.
    """

    bench_contestants: tuple[str, ...]
    bench_reference: str
    bench_description: str
    bench_measures: str

    def bench_scenes(self, count: int, seed: int) -> list[Any]:
        """``count`` scenes of the family's scene model, the same for the same ``seed``."""

    def compare(self, outcome: Any, reference: Any, scene: Any) -> dict[str, float]:
        """How far ``outcome`` is from ``reference`` (both from :meth:`Simulator.run` on
        ``scene``): the key ``error`` holds a distance (max and median over scenes are
        reported); every other key counts disagreements (summed over scenes), named and
        ordered as the table's columns."""


@runtime_checkable
class KnowsFamilies(Protocol):
    """An offline adapter that answers from the scene itself, so it can answer only the scene
    families it knows (``bpb run`` checks before the first call, and leaves it out of its
    default adapters for a family it does not know)."""

    def cannot_answer(self, family: SceneFamily) -> str | None:
        """``None`` when it can answer questions about ``family``'s scenes, else why not (one
        line, e.g. what it could answer instead)."""


@runtime_checkable
class NeedsSimulator(Protocol):
    """An offline adapter that runs the simulator the dataset names (``request.simulator``), as
    ``baseline:oracle`` does: ``bpb run`` refuses it before the first call when that simulator
    is not installed, and leaves it out of its default adapters. Adapters without it run on."""

    def needs_simulator(self) -> bool:
        """Whether its answers come from running the dataset's simulator."""


@runtime_checkable
class UsesRegistry(Protocol):
    """An adapter that looks up plugins itself (a task's expected answer, a family's
    predictions): :meth:`bpb_core.registry.Registry.adapter` hands it the registry that built
    it, so it knows the same tasks and families as the run (a library caller's registry of
    local plugins included)."""

    def use_registry(self, registry: Registry) -> None:
        """Look plugins up in ``registry`` from now on."""


@runtime_checkable
class Preflighting(Protocol):
    """An adapter that can tell before its first call that no call can succeed (no key, an
    unknown provider, a module missing); ``bpb run`` checks every adapter before sending any."""

    def preflight(self) -> str | None:
        """``None`` when calls may be sent, else one line saying what to fix."""


@runtime_checkable
class Describing(Protocol):
    """An adapter whose answers depend on settings beyond its name (model arguments such as a
    reasoning effort): they are recorded in run.json and a resume with others is refused."""

    def settings(self) -> dict[str, Any]:
        """JSON-ready settings that shape the answers (never a secret)."""


@runtime_checkable
class Pricing(Protocol):
    """An adapter that knows before any call whether its replies will carry a cost."""

    @property
    def priced(self) -> bool:
        """True when a price is known (bundled or overridden) for the model."""


@runtime_checkable
class Estimating(Protocol):
    """An adapter that can estimate a request before sending it (``bpb run --dry-run``)."""

    def estimate(self, messages: tuple[Message, ...]) -> tuple[int, float | None]:
        """Input tokens of ``messages`` by the provider's own counting (its image rule
        included) and their input cost in USD (``None`` when no price is known)."""


@runtime_checkable
class Bounding(Protocol):
    """An adapter that can bound what a request may cost before it is sent: ``--max-cost``
    reserves that much per call and never lets reservations pass the cap; ``--dry-run`` shows
    the output cost at the cap."""

    def ceiling(self, messages: tuple[Message, ...], max_tokens: int | None) -> CallCeiling | None:
        """The request's input tokens and cost, and the most output tokens one call may bill
        (``max_tokens`` is the run's cap; the adapter's own arguments may override it) with
        their price; ``None`` when no price is known."""


@runtime_checkable
class AnswersInBrowser(Protocol):
    """A task people can answer in the browser (``bpb human``): it brings its own form widgets
    as a Jinja2 template and turns the posted fields into its answer format; core shows the
    image and the exact prompt beside it, times the answer and stores it like a model's.

    Attributes:
        form_template: Jinja2 source of the task's inputs, rendered with autoescaping and the
            values of :meth:`form_context` plus ``prefix`` (put it before every field name),
            ``image_width`` and ``image_height`` (the input image's pixels; the image is shown
            in an element with id ``scene-image`` inside a positioned box with id
            ``scene-box``, for widgets placed on it).
    """

    form_template: str

    def form_context(self, scene: Any, image: bytes | None) -> dict[str, Any]:
        """The values the form template needs for ``scene`` (JSON-ready)."""

    def read_form(self, fields: Mapping[str, str], scene: Any) -> dict[str, Any]:
        """The answer (the task's answer format) from the posted ``fields`` (names without the
        prefix); raises ``ValueError`` naming the field for anything unexpected."""


@runtime_checkable
class ExplainsErrors(Protocol):
    """A scorer that says in words what an answer got wrong (the failure gallery's text)."""

    def explain(self, rows: pd.DataFrame) -> list[str]:
        """One line per wrong unit of one (run, scene) in ``rows`` (its units of this task)."""


@runtime_checkable
class DrawsOverlay(Protocol):
    """A scorer that marks truth and prediction on the scene's picture (the failure gallery)."""

    def overlay(self, picture: ScenePicture, rows: pd.DataFrame) -> None:
        """Draw on ``picture.image`` and add legend entries to ``picture.legend``."""


@runtime_checkable
class ExplainsInstability(Protocol):
    """A ground truth that says why it is unstable; reports count the scenes each reason
    excludes from the stable subset."""

    @property
    def unstable_reasons(self) -> list[str]:
        """Short names of the stability conditions the scene fails (empty when stable or not
        annotated)."""


@runtime_checkable
class PublishesSchema(Protocol):
    """A task whose answer format has a JSON Schema (published, and offered to providers that
    accept a response schema with ``--structured-output``)."""

    def answer_schema(self) -> dict[str, Any]:
        """The JSON Schema (draft 2020-12) every valid answer, once normalised, satisfies."""


@runtime_checkable
class CountsEvents(Protocol):
    """A family whose outcomes count discrete events, and whose scenes can be made busier: ``bpb
    bench sim`` reports cost per event and cost against events per scene."""

    def events(self, outcome: Any) -> int:
        """The number of events in ``outcome`` (from :meth:`Simulator.run`)."""

    def scaled_scene(self, scene: Any, factor: float) -> Any:
        """``scene`` with more events in the same simulated time (such as faster motion)."""


@runtime_checkable
class RunsMany(Protocol):
    """A simulator with a batch call (``bpb bench sim`` times it beside one call per scene)."""

    def run_many(self, scenes: Sequence[Any], horizon: float | None = None) -> list[Any]:
        """Simulate every scene to ``horizon`` (default: its own): one outcome per scene, in
        order, as :meth:`~bpb_core.interfaces.Simulator.run` returns (motion a picture would
        need may be left out)."""


@runtime_checkable
class TruthOfMany(Protocol):
    """A family that makes the ground truth of many scenes at once (``bpb simulate`` hands it
    its scenes in chunks, when there are many and no stability is asked), e.g. through its
    simulator's :class:`RunsMany` batch call."""

    def ground_truths(
        self, scenes: Sequence[Any], simulator: Simulator, horizon: float | None = None
    ) -> list[GroundTruth]:
        """The truth of each scene, in order, equal to what ``ground_truth(scene, simulator,
        horizon, stability=False)`` gives."""


@runtime_checkable
class ReportsMetrics(Protocol):
    """A scorer with metrics beside its task's accuracy, for a task whose accuracy alone can
    mislead (a rare positive class, say, that a constant answer gets mostly right).

    Reports show them in a table and a chart per task, with the baselines on the same axis,
    and blank them for a run whose task is left out of the leaderboards (too incomplete).

    Attributes:
        metric_notes: Metric column -> one line for the report: what it says, and whether a
            constant or random answer scores a fixed value on it (chance-corrected).
    """

    metric_notes: Mapping[str, str]

    def task_metrics(self, units: pd.DataFrame) -> pd.DataFrame:
        """One row per run of ``units`` (this task's units of answered calls: status ``ok``
        or ``parse_error``) with the run columns ``run, adapter, model, baseline`` first,
        then one column per key of :attr:`metric_notes`, then any counts behind them."""


@runtime_checkable
class DescribesDataset(Protocol):
    """A family that describes its datasets for the dataset card of a published export
    (``bpb export --format hf``)."""

    def dataset_card(self) -> dict[str, Any]:
        """The card's words: ``pretty_name``, ``description`` (Markdown), ``citation``
        (BibTeX), ``license`` (a Hugging Face license id), ``task_categories`` and ``tags``
        (lists of strings); any may be missing."""
