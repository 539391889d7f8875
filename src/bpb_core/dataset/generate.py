"""Generate a dataset (:func:`generate_dataset`) with a scene family plugin.

Generation runs one job per scene on a process pool; each worker asks the family for its scene
and writes the folder, returning a small row, which the parent streams into ``index.csv`` and
``checksums.sha256`` in scene order. Every scene's randomness comes from (seed, horizon, index),
so the same arguments give byte-identical datasets whatever the number of workers.
"""

from __future__ import annotations

import math
import os
import shutil
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.capabilities import Calibrating, DrawingStats, HorizonTally, Tallying
from bpb_core.dataset.jobs import (
    GenerateProgress,
    NoProgress,
    WorkerSetup,
    check_per_horizon,
    run_calibration,
    run_scenes,
    worker_setup,
)
from bpb_core.dataset.manifest import DatasetManifest, DatasetWriter, versions
from bpb_core.errors import (
    BadInput,
    Interrupted,
    PluginBug,
    UnknownName,
    WriteRefused,
    blamed,
)
from bpb_core.interfaces import SceneFamily
from bpb_core.layout import MANIFEST, check_writable_folder, partial_folder
from bpb_core.plugin_calls import (
    family_label,
    family_model,
    json_values,
    loaded_config,
    returned,
    simulator_named,
)
from bpb_core.simulator_spec import SimulatorSpec, parse_spec

if TYPE_CHECKING:
    from bpb_core.registry import Registry


def generate_dataset(
    out: str | Path,
    per_horizon: int,
    horizons: Sequence[float],
    seed: int,
    config: Any = None,
    progress: GenerateProgress | None = None,
    *,
    family: str | None = None,
    stable_only: bool = False,
    workers: int | None = None,
    images: bool = True,
    calibrate: bool = False,
    overwrite: bool = False,
    registry: Registry | None = None,
) -> Path:
    """Generate a dataset folder (SPEC section 4 layout) and return its path.

    The folder is built beside ``out`` under a hidden ``.NAME.partial`` name and renamed at the
    end, so an interrupted generation never leaves a folder that looks complete. A generation
    stopped by bad input (a config whose scenes cannot be made) removes that folder; one the
    system refused to write (a full disk) keeps it, as Ctrl-C does, and says so. Either leaves
    a dataset it was to overwrite as it was.

    Args:
        out: Folder to create; it must not exist or be empty (or be a dataset, with
            ``overwrite``).
        per_horizon: Scenes per horizon (1 to 100,000).
        horizons: Horizons in seconds.
        seed: Dataset seed; scene ``i`` at horizon ``t`` is drawn from (seed, t, i).
        config: The family's config object, a mapping of its fields or a JSON/TOML file;
            ``None`` uses the family's defaults.
        progress: Receives progress; nothing is printed.
        family: Scene family plugin (default: the installed default family).
        stable_only: Keep only scenes whose ground truth is stable: unstable draws are skipped
            and further indices drawn until ``per_horizon`` are kept (scene indices then have
            gaps; the dropped count per horizon is in the manifest).
        workers: Processes (default: all cores); 1 runs in this process. With more, where
            workers are forked, this process makes the first scene before they start, so they
            inherit what it loaded (the family's modules and caches stay loaded here too).
        images: Render the family's images.
        calibrate: Recalibrate the family's sampling first (recorded in the manifest).
        overwrite: Replace an existing dataset folder at ``out``.
        registry: Where the family and simulator come from (default: installed plugins).

    Raises:
        BadInput: Bad arguments or config (the message names the file or field).
        WriteRefused: The system refused a write (names the file, and what is left where).
        Interrupted: Ctrl-C stopped it (a ``KeyboardInterrupt`` saying what is left where: the
            scenes listed so far, whole, in the partial folder; an existing ``out`` as it was).
    """
    with _naming_file(config):
        if registry is None:
            from bpb_core.registry import make_registry

            registry = make_registry(warn=False)  # the CLI reports its warnings itself
        name = family or registry.default_family()
        maker = registry.scene_family(name)
        origin = registry.origin("scene_family", name)
        cfg = loaded_config(maker, origin, config)
        if getattr(cfg, "family", maker.name) != maker.name:
            raise BadInput(
                f"config: family: {cfg.family!r}, but the scene family is {maker.name!r}"
            )
        spec = _check_simulator(registry, maker, origin, cfg)
        hs = _check_args(per_horizon, horizons)
        if calibrate and not isinstance(maker, Calibrating):
            raise BadInput(f"--calibrate: the {name} scene family has nothing to calibrate")
        # Fail before touching the disk; with --calibrate, before the slow calibration, without
        # the horizons (it gives them their settings; checked again on its result)
        checked_config(maker, origin, cfg, () if calibrate else hs)
        progress = progress or NoProgress()
        target = Path(out)
        if target.exists() and (not target.is_dir() or any(target.iterdir())):
            is_dataset = (target / MANIFEST).is_file()
            if not (overwrite and is_dataset):
                hint = (
                    "pass overwrite=True (--overwrite)"
                    if is_dataset
                    else "choose a new or empty folder"
                )
                raise BadInput(f"{target}: --out: exists and is not an empty folder; {hint}")
        check_writable_folder(target)
        with partial_folder(target, "bpb generate") as partial:
            try:
                n_workers = max(1, workers or os.cpu_count() or 1)
                setup = worker_setup(registry, name, partial, seed, cfg, images, spec)
                setup = replace(setup, scenes=per_horizon * len(hs))
                calibration = None
                if isinstance(maker, Calibrating) and calibrate:
                    results = run_calibration(n_workers, setup, hs, progress)
                    cfg, calibration = calibrated(maker, origin, cfg, results)
                    checked_config(maker, origin, cfg, hs)
                    setup = replace(setup, config=cfg)
                tallies = new_tallies(maker, origin, cfg, hs)
                writer = DatasetWriter(
                    partial, hs, maker.index_columns, tallies, origin, family_label(maker)
                )
                try:
                    run_scenes(n_workers, setup, writer, hs, per_horizon, stable_only, progress)
                    _write_stats(maker, setup, writer, tallies, progress)
                finally:
                    writer.close()
                writer.write_manifest(
                    _manifest(maker, setup, writer, hs, per_horizon, stable_only, calibration)
                )
            except BadInput:  # the message says what to change; a half-built folder is of no use
                shutil.rmtree(partial, ignore_errors=True)
                raise
            except WriteRefused as exc:  # left as Ctrl-C leaves it; the user may need the space
                raise WriteRefused(f"{exc}; {_left(target, partial)}") from None
            except KeyboardInterrupt:  # the scenes listed so far are whole; say where they are
                raise Interrupted(_left(target, partial)) from None
            if target.exists():
                shutil.rmtree(target)
            partial.rename(target)
        return target


def _left(target: Path, partial: Path) -> str:
    """What an unfinished generation (a write the system refused, a Ctrl-C) leaves, and where."""
    kept = f"{target} is as it was, " if target.exists() else ""
    return (
        f"{kept}the unfinished dataset is left in {partial} (delete it to free its space; "
        "running the command again starts it afresh)"
    )


@contextmanager
def _naming_file(config: Any) -> Iterator[None]:
    """A config error ("config: balls: ...") names the config's file when it came from one."""
    try:
        yield
    except BadInput as exc:
        text = str(exc)
        if isinstance(config, str | Path) and text.startswith("config: "):
            raise BadInput(f"{config}: {text.removeprefix('config: ')}") from None
        raise


def _check_simulator(
    registry: Registry, family: SceneFamily, origin: str, cfg: Any
) -> SimulatorSpec:
    """The simulator spec (``name`` or ``name:key=value,...``) ``cfg`` names; refused, before any
    worker starts and naming the field, when it does not parse, names an unknown simulator, or
    options it does not take or whose values it refuses (it is built once here to see)."""
    spec = parse_spec(simulator_named(family, origin, cfg), "config: simulator")
    try:
        registry.get("simulator", spec.name)
    except UnknownName as exc:
        raise BadInput(f"config: simulator: {exc}") from None
    if spec.options:
        try:
            registry.simulator(spec.name, spec.options)
        except BadInput as exc:
            raise BadInput(f"config: simulator {spec.spec!r}: {exc}") from None
    return spec


def _check_args(per_horizon: int, horizons: Sequence[float]) -> list[float]:
    check_per_horizon(per_horizon, "per_horizon")
    hs = [float(h) for h in horizons]
    if not hs:
        raise BadInput("horizons: give at least one horizon")
    bad = [h for h in hs if not 0 < h < math.inf]
    if bad:
        raise BadInput(f"horizons: must be positive finite seconds, got {bad[0]:g}")
    if len(set(hs)) != len(hs):
        raise BadInput("horizons: a horizon is listed twice")
    return hs


def _write_stats(
    family: SceneFamily,
    setup: WorkerSetup,
    writer: DatasetWriter,
    tallies: Mapping[float, HorizonTally],
    progress: GenerateProgress,
) -> None:
    if not isinstance(family, DrawingStats):
        return
    progress.phase("stats", 1)
    what = f"scene family {family.name!r}: write_stats()"
    with blamed(setup.origin, what):
        written = family.write_stats(setup.root, setup.config, tallies)
    if not isinstance(written, list | tuple) or not all(isinstance(r, str) for r in written):
        expected = "a list of the paths it wrote (str, relative to the dataset folder)"
        raise returned(setup.origin, what, type(written).__name__, expected)
    missing = [rel for rel in written if not (setup.root / rel).is_file()]
    if missing:
        raise PluginBug(
            f"{setup.origin}: {what} returned {missing[0]!r}, which is no file it wrote "
            "in the dataset folder"
        )
    for rel in written:
        writer.add_file(rel)
    progress.advance()


def _manifest(
    family: SceneFamily,
    setup: WorkerSetup,
    writer: DatasetWriter,
    hs: list[float],
    per_horizon: int,
    stable_only: bool,
    calibration: dict[str, Any] | None,
) -> DatasetManifest:
    summary = writer.summary()
    config = {"family": family.name, **setup.config.model_dump(mode="json")}
    return DatasetManifest(
        seed=setup.seed,
        per_horizon=per_horizon,
        horizons=hs,
        stable_only=stable_only,
        images=setup.images,
        scenes=sum(s.scenes for s in summary.values()),
        summary=summary,
        config=config,
        physics=recorded_physics(family, setup.origin, setup.config),
        calibration=calibration,
        plugins=dict(setup.plugins),
        versions=versions(),
    )


# A scene family's generation hooks, called checked as bpb_core.plugin_calls calls others: each
# runs under blamed() and checks what it returns, so a family's mistake is one line naming its
# plugin (PluginBug, exit 3) instead of a traceback, or an error blamed on the manifest or the
# user's config. A BadInput the family raises about the config passes through.


def checked_config(
    family: SceneFamily, origin: str, config: Any, horizons: Sequence[float]
) -> None:
    """``family.check_config(config, horizons)``: its ``BadInput`` passes through.

    Raises:
        PluginBug: It raised anything else, naming ``origin`` (who supplied the family).
    """
    with blamed(origin, f"{family_label(family)}: check_config()"):
        family.check_config(config, horizons)


def recorded_physics(family: SceneFamily, origin: str, config: Any) -> dict[str, Any]:
    """``family.physics(config)``, checked: a dict that JSON can hold (the manifest records it).

    Raises:
        PluginBug: It raised or returned something else, naming ``origin``.
    """
    what = f"{family_label(family)}: physics()"
    with blamed(origin, what):
        physics = family.physics(config)
    return json_values(origin, what, physics, "what dataset.json")


def new_tallies(
    family: SceneFamily, origin: str, config: Any, horizons: Sequence[float]
) -> dict[float, HorizonTally]:
    """A ``family.new_tally(config, h)`` per horizon (none when the family does not tally),
    checked: each has ``add()`` and ``summary()``, which the writer calls next, checked too.

    Raises:
        PluginBug: ``new_tally()`` raised or returned something else, naming ``origin``.
    """
    if not isinstance(family, Tallying):
        return {}
    tallies = {}
    for horizon in horizons:
        what = f"{family_label(family)}: new_tally({horizon:g})"
        with blamed(origin, what):
            tally = family.new_tally(config, horizon)
        if not all(callable(getattr(tally, name, None)) for name in ("add", "summary")):
            expected = "a tally with add(row) and summary()"
            raise returned(origin, what, type(tally).__name__, expected)
        tallies[horizon] = tally
    return tallies


def calibrated(
    family: Calibrating, origin: str, config: Any, results: Mapping[float, Any]
) -> tuple[Any, dict[str, Any]]:
    """``family.apply_calibration(config, results)``, checked: the calibrated config (an
    instance of the family's ``config_model``) and the manifest's record (a dict).

    Raises:
        PluginBug: It raised or returned something else, naming ``origin``.
    """
    what = f"{family_label(family)}: apply_calibration()"
    with blamed(origin, what):
        applied = family.apply_calibration(config, results)
    model = family_model(family, "config_model")
    if isinstance(applied, tuple) and len(applied) == 2:
        new, record = applied
        if (model is None or isinstance(new, model)) and isinstance(record, dict):
            return new, record
    got = type(applied).__name__
    if isinstance(applied, tuple) and len(applied) == 2:
        got = f"({', '.join(type(part).__name__ for part in applied)})"
    expected = "the config" if model is None else model.__name__
    raise returned(origin, what, got, f"({expected}, a dict: the manifest's calibration record)")
