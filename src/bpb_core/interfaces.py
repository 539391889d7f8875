"""The interfaces plugins implement: SceneFamily, Simulator, Task, Scorer, Diagnostic and
ModelAdapter, and the values that pass between them.

They are :class:`typing.Protocol` classes: a plugin need not inherit from them, only provide the
attributes and methods. Core never looks inside a scene or its ground truth: it reads them with
the family's models, hands them to the family's simulator and to the tasks, and keeps only
``scene_id``, ``horizon`` and the truth's ``stable`` flag for itself. Parameters typed ``Any``
below carry a family's own scene, ground truth or config objects.

Optional capabilities are separate protocols (:mod:`bpb_core.capabilities`); core checks for
them with ``isinstance`` and does without when a plugin lacks one.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

# isinstance() never runs a plugin's properties, as on Python 3.12 (see bpb_core.capabilities)
from typing_extensions import Protocol, runtime_checkable

if TYPE_CHECKING:
    import pandas as pd

    from bpb_core.model_calls import Message, ModelRequest, ModelResponse
    from bpb_core.registry import SuiteInfo
    from bpb_core.scored_units import UnitRow

InputMode = Literal["image", "image+state", "state"]


@dataclass(frozen=True)
class PromptOptions:
    """How a prompt is built.

    Attributes:
        input_mode: ``image`` (the paper), ``image+state`` or ``state`` (text only).
        cot: Ask for reasoning before the JSON answer.
        force_numeric: Ask for numbers where the task would otherwise allow ``null``.
        escalation: 0 on the first ask; higher on re-asks after a malformed answer.
    """

    input_mode: InputMode = "image"
    cot: bool = False
    force_numeric: bool = False
    escalation: int = 0


@dataclass(frozen=True)
class ParsedAnswer:
    """A validated answer in the task's answer format, and which extraction rule found it."""

    value: dict[str, Any]
    rule: str


class Scene(Protocol):
    """An initial state of some scene family: the content of a scene's ``init.json``."""

    @property
    def scene_id(self) -> str:
        """Unique within its dataset (``h3_0007``)."""

    @property
    def horizon(self) -> float:
        """Seconds to simulate; questions are about ``[0, horizon]``."""


class GroundTruth(Protocol):
    """What truly happens in a scene by its horizon: the content of ``final.json``."""

    @property
    def scene_id(self) -> str:
        """The scene's id."""

    @property
    def stable(self) -> bool | None:
        """Whether no label flips under small perturbations (``None``: not annotated)."""

    def model_dump_json(self, *, indent: int | None = None) -> str:
        """The ``final.json`` text."""


class GeneratedScene(Protocol):
    """One scene made by a family's :meth:`SceneFamily.make_scene`, not yet written."""

    @property
    def truth(self) -> GroundTruth:
        """Its ground truth (``truth.stable`` decides ``--stable-only``)."""

    @property
    def row(self) -> Mapping[str, object]:
        """Its cells of ``index.csv``, keyed by :attr:`SceneFamily.index_columns`."""

    def files(self, images: bool) -> dict[str, bytes]:
        """The scene folder's files by name, ``init.json`` and ``final.json`` first; images
        only when ``images`` (rendering is skipped for scenes that are not kept)."""


@runtime_checkable
class Simulator(Protocol):
    """A physics engine for the scenes of one family (the family its record names)."""

    name: str

    def run(self, scene: Any, horizon: float | None = None) -> Any:
        """Simulate ``scene`` to ``horizon`` (default: the scene's own); return an outcome the
        family understands."""


@runtime_checkable
class SceneFamily(Protocol):
    """A kind of scene: its files, how to draw one, and what truly happens in it.

    Core runs the jobs, lays out the folders and writes the manifest, index and checksums;
    everything about the scenes themselves comes from here.

    Attributes:
        name: The family's name (``bpb generate --family NAME``); recorded in the dataset
            config under ``family``.
        scene_model: Pydantic model of ``init.json`` (read, validated, published as a schema).
        truth_model: Pydantic model of ``final.json``.
        config_model: Pydantic model of the generation config (recorded in the manifest).
        input_image: File name of the image models see (``init.png``); ``None`` when the
            family renders no images (then only the ``state`` input mode works).
        image_names: Every image a scene folder may hold.
        index_columns: The family's columns of ``index.csv`` (between ``index`` and
            ``stable``).
    """

    name: str
    scene_model: type[Any]
    truth_model: type[Any]
    config_model: type[Any]
    input_image: str | None
    image_names: tuple[str, ...]
    index_columns: tuple[str, ...]

    def load_config(self, source: Any) -> Any:
        """A config from ``None`` (defaults), a JSON/TOML file path, a mapping of fields or a
        config object; raises :class:`~bpb_core.errors.BadInput` naming the file and field."""

    def check_config(self, config: Any, horizons: Sequence[float]) -> None:
        """Raise :class:`~bpb_core.errors.BadInput` before anything is written when
        ``config`` cannot make scenes at ``horizons``. With ``--calibrate`` it is called first
        with no horizons (check what calibration does not set), then with the horizons on the
        calibrated config."""

    def simulator_name(self, config: Any) -> str:
        """The simulator plugin the config asks for: its name, or ``name:key=value,...``
        with the options it is built with (:mod:`bpb_core.simulator_spec`), which the
        manifest's config should record."""

    def make_scene(
        self, config: Any, simulator: Simulator, seed: int, horizon: float, index: int
    ) -> GeneratedScene:
        """Scene ``index`` at ``horizon``, drawn from a generator seeded by (seed, horizon,
        index) alone, simulated and annotated. Its ``scene_id`` must be
        :func:`bpb_core.layout.scene_id` ``(horizon, index)`` (``h2_0003``): the name of the
        folder it lands in."""

    def physics(self, config: Any) -> dict[str, Any]:
        """The world the config describes, recorded under ``physics`` in the manifest."""

    def ground_truth(
        self, scene: Any, simulator: Simulator, horizon: float | None = None, *, stability: bool
    ) -> GroundTruth:
        """What ``simulator`` says happens in ``scene`` by ``horizon`` (default: its own), with
        the stability annotation when ``stability``."""


@runtime_checkable
class Task(Protocol):
    """A question about a scene of one family (the family its record names).

    Attributes:
        name: Short name (what ``--tasks`` takes).
        default_cot: Whether chain of thought is on by default.
    """

    name: str
    default_cot: bool

    def messages(
        self, scene: Any, image: bytes | None, options: PromptOptions
    ) -> tuple[Message, ...]:
        """Build the prompt from the scene alone (never from ground truth)."""

    def parse(self, text: str, scene: Any, options: PromptOptions) -> ParsedAnswer:
        """Extract and validate the answer; raise :class:`~bpb_core.errors.ParseFailure`."""

    def expected(self, truth: Any) -> dict[str, Any]:
        """The correct answer, in the task's answer format, from the family's ground truth."""


@runtime_checkable
class ModelAdapter(Protocol):
    """Talks to one model. Raises :mod:`bpb_core.errors` model errors on failure."""

    name: str

    async def complete(self, request: ModelRequest) -> ModelResponse:
        """Send one request and return the reply."""


@runtime_checkable
class Scorer(Protocol):
    """Scores one task's answers against ground truth, in two steps.

    1. :meth:`units` cuts one answer into scored units (:class:`~bpb_core.scored_units.UnitRow`,
       e.g. one per object, label or position), pairing each with its true label. It is
       called once per (run, scene, task) while :func:`bpb_core.results.load_results` reads
       the files.
    2. :meth:`score` marks a whole frame of units at once, vectorised: it must score one
       million rows in well under two seconds. Its input has the columns of
       :data:`bpb_core.scored_units.SCORER_INPUT` plus the scorer's own :attr:`columns`; it
       returns a frame with the same index and the columns ``correct`` (bool) and
       ``distance`` (float64, NaN where no distance applies).

    A unit can only be correct when the call's ``status`` is ``ok``.

    Attributes:
        name: Scorer name.
        task: Name of the task it scores.
        scene_rule: How unit results make a scene's score: ``mean`` (share of correct units)
            or ``all`` (1 only when every unit is correct).
        columns: The scorer's extra unit columns and their pandas dtypes, in the order of
            :attr:`UnitRow.values <bpb_core.scored_units.UnitRow>`.
    """

    name: str
    task: str
    scene_rule: Literal["mean", "all"]
    columns: Mapping[str, str]

    def units(self, answer: Mapping[str, Any] | None, truth: Any, scene: Any) -> list[UnitRow]:
        """The scored units of one answer (``None`` = no answer), in a fixed order."""

    def score(self, units: pd.DataFrame) -> pd.DataFrame:
        """Columns ``correct`` and ``distance`` for every row of ``units``."""


class ScoredResults(Protocol):
    """What a diagnostic reads: the scored frames (see :mod:`bpb_core.results.frames`)."""

    @property
    def units(self) -> pd.DataFrame:
        """One row per scored unit of every expected (run, scene, task)."""

    @property
    def calls(self) -> pd.DataFrame:
        """One row per (run, scene, task) with status, tokens, cost and latency."""

    @property
    def suites(self) -> tuple[SuiteInfo, ...]:
        """The installed suites all of whose tasks appear in ``units``."""


@runtime_checkable
class Diagnostic(Protocol):
    """A table derived from scored results, shown in reports when one of its tasks ran.

    Attributes:
        name: File and JSON name.
        title: Section heading.
        percent: Columns shown as percentages.
        terminal: Columns ``bpb report`` prints in the terminal (empty: HTML and files only).
    """

    name: str
    title: str
    percent: tuple[str, ...]
    terminal: tuple[str, ...]

    def table(self, results: ScoredResults) -> pd.DataFrame:
        """The table: one row per run (or per run and something else), with the run columns
        ``run, adapter, model, baseline`` first."""

    def chart(self, table: pd.DataFrame) -> bytes | None:
        """A PNG of the table, or ``None``."""
