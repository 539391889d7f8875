"""``bpb view``: the (run, scene, task) pairs of some runs, filtered, everything about one pair,
and the Starlette app that serves them.

``GET /`` lists pairs (query parameters ``dataset``, ``model``, ``task``, ``horizon``,
``stable``, ``verdict``, ``page``), a section per dataset (runs over different datasets answered
different questions), ``GET /pair/<run>/<scene_id>/<task>`` shows one, ``GET /image/...`` and
``GET /overlay/...`` serve its pictures. An unknown filter value is a 400 naming it. A pair's
items show the scorer's own unit columns beside truth and answer (an ``<name>_x``/``<name>_y``
pair as one point), and the distance where the scorer gives one.

Pairs come from the results frames (:func:`~bpb_core.results.frames.load_results`); a pair is
``correct`` when every scored unit of it is, ``unanswered`` when the run has no answer for it
(missing, or an API error), else ``wrong``. A pair's page rebuilds the exact prompt from the
task (with the input mode, chain-of-thought setting and escalation of each attempt), lists every
attempt from the attempts log, and has the scene family draw the truth with each scorer's
marks (as the report's failure gallery does).
"""

from __future__ import annotations

import json
from collections import defaultdict
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any
from urllib.parse import urlencode

import pandas as pd
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import HTMLResponse, Response
from starlette.routing import Route

from bpb_core.errors import PluginBug
from bpb_core.interfaces import PromptOptions
from bpb_core.layout import SceneKey
from bpb_core.model_calls import prompt_text
from bpb_core.plugin_calls import prompt_messages
from bpb_core.report.sections import drawing
from bpb_core.results.frames import Results, load_results
from bpb_core.run_folder import REPLIED, AnswerRecord, read_answer, read_attempts
from bpb_core.web import error_page, loopback_only, plugin_bug_page, render

if TYPE_CHECKING:
    from bpb_core.registry import Registry
    from bpb_core.results.reading import RunFolder

PAGE_SIZE = 100
VERDICTS = ("correct", "wrong", "unanswered")
STABILITY = ("stable", "unstable")


class QueryError(ValueError):
    """A filter value the runs do not have; the message names the parameter."""


@dataclass(frozen=True)
class PairView:
    """Everything shown about one (run, scene, task)."""

    run: RunFolder
    run_id: int
    key: SceneKey
    task: str
    record: AnswerRecord | None
    prompts: list[tuple[int, str]]
    attempts: list[dict[str, Any]]
    units: pd.DataFrame
    verdict: str
    prompt_note: str = ""
    dataset: str = ""
    """The run's dataset, as the index names it."""

    @property
    def answer_json(self) -> str:
        """The parsed answer, pretty-printed (empty without one)."""
        if self.record is None or self.record.answer is None:
            return ""
        return json.dumps(self.record.answer, indent=1)


@dataclass
class Viewer:
    """Runs loaded for browsing."""

    results: Results
    registry: Registry
    pairs: pd.DataFrame
    _attempts: dict[int, dict[tuple[str, str], list[dict[str, Any]]]] = field(default_factory=dict)

    @classmethod
    def load(cls, paths: list[Path], registry: Registry) -> Viewer:
        """Read and score ``paths`` (run folders or folders of them)."""
        results = load_results(paths, registry=registry)
        return cls(results, registry, _pairs(results.units, dataset_names(results)))

    def choices(self) -> dict[str, list[str]]:
        """The values each filter can take."""
        frame = self.pairs
        return {
            "dataset": sorted(str(v) for v in frame["dataset"].unique()),
            "model": sorted(str(v) for v in frame["adapter"].unique()),
            "task": sorted(str(v) for v in frame["task"].unique()),
            "horizon": [f"{h:g}" for h in sorted(frame["horizon"].unique())],
            "stable": list(STABILITY),
            "verdict": list(VERDICTS),
        }

    def select(self, query: Mapping[str, str]) -> tuple[pd.DataFrame, int]:
        """The pairs matching ``query`` (one page of them) and how many match.

        Raises:
            QueryError: An unknown parameter or a value no pair has.
        """
        choices = self.choices()
        frame = self.pairs
        for name, value in query.items():
            if name == "page" or value == "":
                continue
            if name not in choices:
                raise QueryError(f"{name[:40]}: not a filter (filters: {', '.join(choices)})")
            if value not in choices[name]:
                raise QueryError(f"{name}: no pair has {value[:40]!r}")
            frame = frame[_mask(frame, name, value)]
        page = _page(query.get("page", "1"))
        start = (page - 1) * PAGE_SIZE
        return frame.iloc[start : start + PAGE_SIZE], len(frame)

    def pair(self, run_id: int, scene_id: str, task: str) -> PairView:
        """One pair.

        Raises:
            QueryError: No such run, scene or task among the loaded runs.
        """
        if not 0 <= run_id < len(self.results.runs):
            raise QueryError(f"run {run_id}: no such run")
        run = self.results.runs[run_id]
        rows = self._rows(run.label, scene_id, task)
        if rows.empty:
            raise QueryError(f"{scene_id[:40]} / {task[:20]}: not a pair of run {run.label}")
        key = SceneKey(float(rows["horizon"].iloc[0]), int(rows["index"].iloc[0]))
        record = read_answer(key.dir(run.path) / f"{task}.json")
        attempts = self._attempts_of(run_id).get((scene_id, task), [])
        try:
            prompts, note = self._prompts(run, key, task, record, attempts), ""
        except QueryError as exc:  # the input image is gone: the rest of the page still shows
            prompts, note = [], f"not rebuilt: {exc}"
        verdict = _pairs(rows, dataset_names(self.results))["verdict"].iloc[0]
        units = self._items(rows, task)
        dataset = dataset_names(self.results)[run.dataset_id]
        return PairView(
            run, run_id, key, task, record, prompts, attempts, units, str(verdict), note, dataset
        )

    def _items(self, rows: pd.DataFrame, task: str) -> pd.DataFrame:
        """The pair's items as shown: item, truth, answer, the verdict (``unanswered`` where the
        run has no answer), the distance (where the scorer gives one) and the scorer's own
        columns (``<name>_x``/``<name>_y`` as one point ``(x, y)``; empty where absent)."""
        own = list(self.registry.scorer_for(task).columns) if task in self.results.tasks else []
        answered = rows["status"].isin(REPLIED)
        shown = pd.DataFrame(
            {
                "item": rows["unit"].astype(str),
                "truth": rows["truth"].map(_cell),
                "answer": rows["pred"].where(answered).map(_cell),
                "verdict": rows["correct"].map(lambda c: "right" if c else "wrong"),
            }
        )
        shown["verdict"] = shown["verdict"].where(answered.to_numpy(), "unanswered")
        if rows["distance"].notna().any():
            shown["distance"] = rows["distance"].map(lambda d: _cell(d, "{:.4f}"))
        for name in own:
            if name.endswith("_y") and name[:-1] + "x" in own:
                continue
            if name.endswith("_x") and name[:-1] + "y" in own:
                xs, ys = rows[name], rows[name[:-1] + "y"]
                points = [_point(x, y) for x, y in zip(xs, ys, strict=True)]
                shown[f"{name[:-2]} (x, y)"] = points
            else:
                shown[name] = rows[name].map(_cell)
        return shown.reset_index(drop=True)

    def image(self, run_id: int, scene_id: str) -> bytes:
        """The input image the run's models were shown for ``scene_id``.

        Raises:
            QueryError: No such run or scene, or the dataset has no such image (generated
                without images, or the file was moved).
        """
        run, key = self._scene(run_id, scene_id)
        name = run.family.input_image if run.family is not None else None
        if name is None:
            raise QueryError(f"the {run.label} dataset has no images")
        path = key.dir(run.dataset) / name
        try:
            return path.read_bytes()
        except OSError as exc:
            raise QueryError(f"{path}: cannot read the input image: {exc.strerror}") from None

    def overlay(self, run_id: int, scene_id: str, task: str) -> bytes:
        """The scene drawn by its family with the task's truth and prediction marks."""
        view = self.pair(run_id, scene_id, task)
        rows = self._rows(view.run.label, scene_id, task)
        scorer = self.registry.scorer_for(task)
        origin = self.registry.scorer_entry(task).origin
        return drawing(view.run, view.key, {task: rows}, {task: scorer}, {task: origin})

    def _rows(self, label: str, scene_id: str, task: str) -> pd.DataFrame:
        units = self.results.units
        pick = (units["run"] == label) & (units["scene_id"] == scene_id) & (units["task"] == task)
        return units[pick]

    def _scene(self, run_id: int, scene_id: str) -> tuple[RunFolder, SceneKey]:
        if not 0 <= run_id < len(self.results.runs):
            raise QueryError(f"run {run_id}: no such run")
        run = self.results.runs[run_id]
        for key in run.scene_keys:
            if key.scene_id == scene_id:
                return run, key
        raise QueryError(f"{scene_id[:40]}: not a scene of run {run.label}")

    def _attempts_of(self, run_id: int) -> dict[tuple[str, str], list[dict[str, Any]]]:
        if run_id not in self._attempts:
            found: dict[tuple[str, str], list[dict[str, Any]]] = defaultdict(list)
            for entry in read_attempts(self.results.runs[run_id].path):
                found[(str(entry.get("scene_id")), str(entry.get("task")))].append(entry)
            self._attempts[run_id] = dict(found)
        return self._attempts[run_id]

    def _prompts(
        self, run: RunFolder, key: SceneKey, task: str, record: AnswerRecord | None,
        attempts: list[dict[str, Any]],
    ) -> list[tuple[int, str]]:  # fmt: skip
        """The prompt text of each escalation level the attempts used (0 when none)."""
        if task not in self.registry.names("task"):
            return []
        component = self.registry.task(task)
        scene, _ = run.truth(key)
        options = run.manifest.get("options") or {}
        mode = record.input_mode if record else str(options.get("input_mode", "image"))
        cot = record.cot if record else component.default_cot
        image = None if mode == "state" else self.image(self.results.runs.index(run), key.scene_id)
        levels = sorted({_level(a.get("escalation")) for a in attempts} or {0})
        out = []
        for level in levels:
            prompt = PromptOptions(mode, cot, bool(options.get("force_numeric", False)), level)  # type: ignore[arg-type]
            origin = self.registry.origin("task", task)
            messages = prompt_messages(component, origin, scene, image, prompt)
            out.append((level, prompt_text(messages)))
        return out


def dataset_names(results: Results) -> dict[str, str]:
    """Each dataset's name on the pages: its folder and the start of its hash."""
    names = {}
    for run in results.runs:
        hashed = run.dataset_id if run.dataset_id != str(run.dataset) else ""
        names[run.dataset_id] = (
            f"{run.dataset.name} ({hashed[:12]})" if hashed else str(run.dataset)
        )
    return names


def _cell(value: object, form: str = "{}") -> str:
    """A unit value as text: empty for a missing one (NaN, None)."""
    if value is None or (isinstance(value, float) and value != value):
        return ""
    return form.format(value) if isinstance(value, float) else str(value)


def _point(x: object, y: object) -> str:
    if not isinstance(x, float) or not isinstance(y, float) or x != x or y != y:
        return ""
    return f"({x:.4f}, {y:.4f})"


def _pairs(units: pd.DataFrame, datasets: Mapping[str, str]) -> pd.DataFrame:
    """One row per (run, scene, task) with its verdict and its dataset's name, by dataset."""
    units = units.assign(dataset=units["dataset"].astype(str).map(datasets))
    keys = ["dataset", "run", "adapter", "model", "task", "horizon", "index", "scene_id"]
    grouped = units.groupby(keys, observed=True, sort=True)
    frame = grouped.agg(
        stable=("stable", "first"),
        status=("status", "first"),
        units=("correct", "size"),
        right=("correct", "sum"),
    ).reset_index()
    answered = frame["status"].isin(REPLIED)
    frame["verdict"] = "wrong"
    frame.loc[answered & (frame["right"] == frame["units"]), "verdict"] = "correct"
    frame.loc[~answered, "verdict"] = "unanswered"
    return frame


def _mask(frame: pd.DataFrame, name: str, value: str) -> pd.Series:
    if name == "model":
        return frame["adapter"].astype(str) == value
    if name == "horizon":
        return frame["horizon"].map(lambda h: f"{h:g}") == value
    if name == "stable":
        return frame["stable"].fillna(False).astype(bool) == (value == "stable")
    return frame[name].astype(str) == value


def _level(value: object) -> int:
    """An attempt's escalation level as logged; 0 for anything but a whole number >= 0 (a
    hand-edited or foreign log)."""
    if isinstance(value, int) and not isinstance(value, bool) and 0 <= value <= 1_000_000:
        return value
    return 0


def _page(value: str) -> int:
    if not (value.isascii() and value.isdigit()) or not 1 <= int(value) <= 1_000_000:
        raise QueryError("page: expected a page number")
    return int(value)


def viewer_app(viewer: Viewer) -> Starlette:
    """The app browsing ``viewer``'s runs."""
    run_ids = {run.label: i for i, run in enumerate(viewer.results.runs)}

    async def index(request: Request) -> Response:
        query = dict(request.query_params)
        try:
            rows, total = viewer.select(query)
        except QueryError as exc:
            return error_page(str(exc))
        page = int(query.get("page") or 1)
        keep = {k: v for k, v in query.items() if k != "page" and v}
        html = render(
            "view_index.html",
            viewer=viewer,
            rows=rows.to_dict(orient="records"),
            run_ids=run_ids,
            total=total,
            page=page,
            pages=max(1, -(-total // PAGE_SIZE)),
            query=keep,
            choices=viewer.choices(),
            link=lambda **change: "?" + urlencode({**keep, **change}),
        )
        return HTMLResponse(html)

    async def pair(request: Request) -> Response:
        p = request.path_params
        view = viewer.pair(int(p["run"]), p["scene_id"], p["task"])
        return HTMLResponse(render("view_pair.html", view=view))

    async def image(request: Request) -> Response:
        p = request.path_params
        return Response(viewer.image(int(p["run"]), p["scene_id"]), media_type="image/png")

    async def overlay(request: Request) -> Response:
        p = request.path_params
        png = viewer.overlay(int(p["run"]), p["scene_id"], p["task"])
        if not png:
            return error_page("the scene family draws no picture", 404)
        return Response(png, media_type="image/png")

    async def not_found(request: Request, exc: Exception) -> Response:
        return error_page(str(exc), 404)

    return Starlette(
        routes=[
            Route("/", index),
            Route("/pair/{run:int}/{scene_id}/{task}", pair),
            Route("/image/{run:int}/{scene_id}", image),
            Route("/overlay/{run:int}/{scene_id}/{task}", overlay),
        ],
        middleware=[loopback_only()],
        exception_handlers={QueryError: not_found, PluginBug: plugin_bug_page},
    )
