"""Simulate scene files: the library behind ``bpb simulate``.

Inputs are ``init.json`` files, scene folders holding one, ``final.json`` files (the ``init.json``
beside them is simulated) or dataset folders (every ``h{t}/scene_{i}`` in dataset order). Scenes
are read with the models of the simulator's scene family, and results come back in input order,
one ground truth (the family's ``final.json`` model) per scene. Every user mistake is a
:class:`~bpb_core.errors.BadInput` naming the file and the field, e.g.
``scenes/x.json: <field path>: what is wrong``.
"""

from __future__ import annotations

import contextlib
import errno
import math
import os
import stat
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from bpb_core.dataset.jobs import check_workers, started_pool, worker_signals
from bpb_core.dataset.manifest import check_simulator
from bpb_core.dataset.reader import dataset_family, dataset_simulator_spec
from bpb_core.errors import BadInput, BpbError, PluginBug, blamed
from bpb_core.layout import FINAL, INIT, MANIFEST, horizon_label, scene_places
from bpb_core.plugin_calls import loaded_config, simulated_truth, simulator_named
from bpb_core.scored_units import object_origin
from bpb_core.simulator_spec import SimulatorSpec, parse_spec
from bpb_core.validated_files import read_model

if TYPE_CHECKING:
    from bpb_core.capabilities import WritesTruthLines
    from bpb_core.interfaces import GroundTruth, SceneFamily, Simulator
    from bpb_core.registry import Registry


def scene_files(paths: Iterable[str | Path]) -> list[Path]:
    """The ``init.json`` files named by ``paths``, expanded in input order."""
    return [Path(name) for name in _scene_names(paths)]


_SPECIAL: set[str] = set()
"""Named paths that are not regular files (a pipe such as ``<(...)``, a device): read to the end
of their data, where a short read does not mean the end, and once each (:data:`_PIPED`)."""

_PIPED: dict[tuple[int, int], bytes] = {}
"""What each of :data:`_SPECIAL` held, by device and inode, for one call: a pipe is empty when
read again, so a pipe named twice (``bpb simulate /dev/stdin /dev/stdin``, or ``/dev/stdin``
and ``/dev/fd/0``) is read once and its content stands for each naming, as a file named twice
gives the same scene twice."""


def _scene_names(paths: Iterable[str | Path], *, ahead: bool = False) -> list[str]:
    """:func:`scene_files` as strings, with no path objects and the kind of each named path
    found from its folder's listing when many names share that folder (see :func:`_kinds`),
    else with one ``stat``: with ten thousand files named on the command line, a ``stat`` each
    was a tenth of ``bpb simulate``'s time per scene. ``ahead``: find the kind of each path by
    reading it instead (:func:`_probe`), keeping the bytes of a regular file for
    :func:`_read_all` (:data:`_AHEAD`), up to :data:`AHEAD_MAX` bytes; then list and ``stat``
    the rest. Reading a file costs what reading it later would, so this saves the ``stat``, or
    the folder's listing."""
    names = [os.fspath(raw) for raw in paths]
    _PIPED.clear()  # a pipe of an earlier call is not this call's
    _AHEAD.clear()
    kinds = {} if ahead else _kinds(names)
    found: list[str] = []
    room = AHEAD_MAX if ahead else 0
    for at, name in enumerate(names):
        mode = kinds.get(name)
        if mode is None and room > 0:
            mode = _probe(name)
            room -= len(_AHEAD.get(name, b""))
            if room <= 0:
                kinds = _kinds(names[at + 1 :])
        if mode is None:
            try:
                mode = os.stat(name).st_mode
            except (OSError, ValueError):
                raise BadInput(f"{name}: no such file or directory") from None
        if not stat.S_ISREG(mode):
            _SPECIAL.add(name)
        if stat.S_ISDIR(mode):
            found.extend(_folder_scenes(Path(name)))
        elif name.endswith(FINAL) and os.path.basename(name) == FINAL:
            found.append(os.path.join(os.path.dirname(name), INIT))
        else:
            found.append(name)
    return found


_AHEAD: dict[str, bytes] = {}
"""The bytes of the regular files :func:`_probe` read while listing, by name, for one call;
:func:`_read_all` and :func:`_line` take them out."""

AHEAD_MAX = 1 << 26
"""Bytes of scene files read while listing at most (64 MiB, about 40,000 scenes): past that,
the rest are ``stat``-ed and read later, so a huge list does not sit in memory."""

_OPEN = os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_BINARY", 0) | getattr(os, "O_CLOEXEC", 0)


def _probe(name: str) -> int | None:
    """The type bits of ``name`` found by opening and reading it, which costs one path lookup
    where a ``stat`` then an open cost two (most of the time of listing and reading a scene
    file): ``S_IFREG`` with its bytes kept in :data:`_AHEAD`, ``S_IFDIR``, 0 for a pipe read to
    its end (kept in :data:`_PIPED`), or ``None`` when ``stat`` is to decide.

    The open does not wait (``O_NONBLOCK``): a named pipe with no writer yet opens at once, reads
    empty and is left to ``stat`` and the blocking open of :func:`_special_data`, which waits
    for one. A pipe that has a writer, or one whose writer waited in its own open (which this
    open let through), is read to its end here: closing it unread would leave that writer
    writing into a pipe nobody reads."""
    try:
        fd = os.open(name, _OPEN)
    except (OSError, ValueError):
        return None
    try:
        try:
            data = os.pread(fd, _READ, 0)
        except IsADirectoryError:
            return stat.S_IFDIR
        except OSError as exc:
            return _probed_pipe(fd) if exc.errno == errno.ESPIPE else None
        while len(data) % _READ == 0 and data:  # a full read: there may be more
            more = os.pread(fd, _READ, len(data))
            if not more:
                break
            data += more
        _AHEAD[name] = data
        return stat.S_IFREG
    except OSError:
        _AHEAD.pop(name, None)
        return None
    finally:
        os.close(fd)


def _probed_pipe(fd: int) -> int | None:
    """0 for the pipe (or other unseekable file) open at ``fd`` once its data is in
    :data:`_PIPED`, read here to its end unless a naming of the same pipe read it before;
    ``None`` when it held nothing (no writer yet: see :func:`_probe`)."""
    info = os.fstat(fd)
    key = (info.st_dev, info.st_ino)
    if key in _PIPED:
        return 0
    os.set_blocking(fd, True)
    data = b"".join(iter(lambda: os.read(fd, _READ), b""))
    if not data:
        return None
    _PIPED[key] = data
    return 0


LISTED_MIN = 32
"""Named paths in one folder from which that folder is listed instead of ``stat``-ing each."""


def _kinds(names: Sequence[str]) -> dict[str, int]:
    """The type bits (``S_IFREG``, ``S_IFDIR``, or 0 for a pipe, a device or a socket) of the
    names that lie :data:`LISTED_MIN` or more to a folder, read from the folder's listing: a
    directory entry knows its type without a ``stat`` (one system call per file, several
    microseconds here). Symbolic links, ``.``, ``..``, names ending in a separator and
    anything the listing does not show are left out, for ``stat`` to settle."""
    by_folder: dict[str, dict[str, str]] = {}
    sep = os.sep
    for name in names:
        if os.altsep and os.altsep in name:
            continue
        head, root, tail = name.rpartition(sep)  # not os.path.split: a third of the time
        by_folder.setdefault(head or root, {})[tail] = name
    kinds: dict[str, int] = {}
    for folder, wanted in by_folder.items():
        if len(wanted) < LISTED_MIN:
            continue
        left = len(wanted)
        try:
            with os.scandir(folder or os.curdir) as entries:
                for entry in entries:
                    named = wanted.get(entry.name)
                    if named is None:
                        continue
                    if not entry.is_symlink():
                        kinds[named] = (
                            stat.S_IFDIR
                            if entry.is_dir(follow_symlinks=False)
                            else stat.S_IFREG
                            if entry.is_file(follow_symlinks=False)
                            else 0
                        )
                    left -= 1
                    if not left:
                        break
        except OSError:
            continue
    return kinds


def _folder_scenes(folder: Path) -> list[str]:
    if (folder / INIT).is_file():
        return [str(folder / INIT)]
    top, sep = str(folder), os.sep
    labels: dict[float, str] = {}
    found = []
    for horizon, index in scene_places(folder):  # the paths of SceneKey.dir, as strings
        label = labels.get(horizon)
        if label is None:
            label = labels[horizon] = f"{top}{sep}{horizon_label(horizon)}"
        found.append(f"{label}{sep}scene_{index:04d}{sep}{INIT}")
    if not found:
        raise BadInput(f"{folder}: no {INIT} and no dataset scene folders (h<t>/scene_<i>) in it")
    return found


def simulate_scene(
    scene: Any,
    simulator: Simulator,
    family: SceneFamily,
    horizon: float | None = None,
    *,
    stability: bool = False,
    origin: str | None = None,
) -> GroundTruth:
    """Ground truth of ``scene`` at ``horizon`` (default: the scene's own) from ``simulator``.

    Raises:
        PluginBug: The family raised or returned something other than its ``truth_model``,
            naming ``origin`` (who supplied it; default: its module).
    """
    who = origin if origin is not None else object_origin(family)
    truth: GroundTruth = simulated_truth(
        family, who, scene, simulator, horizon=horizon, stability=stability
    )
    return truth


@dataclass(frozen=True)
class Prepared:
    """A simulator with its family, resolved once for many scenes, and who supplied the family
    (``Registered.origin``), for one-line plugin errors."""

    simulator: Simulator
    family: SceneFamily
    origin: str
    names: Mapping[str, str] = field(default_factory=dict)
    """How the user set each simulator option, for messages (see :func:`prepare`)."""


def prepare(
    horizon: float | None,
    simulator: str | Simulator | None,
    registry: Registry | None,
    options: Mapping[str, Any] | None,
    files: Sequence[Path] = (),
    names: Mapping[str, str] | None = None,
) -> Prepared:
    """Resolve ``simulator`` (a name or spec with options, ``pymunk:dt=0.0005``, where
    ``options`` win; an object; or ``None``: the simulator the scenes' dataset
    was made with, with the options its config gives it (``options`` win), else the default
    family's) and its scene family: the family of that dataset, which reads the scenes and
    makes their truth as it did when the dataset was generated, whatever family the simulator
    itself is registered for; for loose scene files the simulator's family (else the default
    one). ``names``: how the caller's user sets each option (``{"dt": "--dt"}``), for messages;
    an option from the dataset's config is named there.

    Raises:
        BadInput: A bad horizon, an unknown simulator (one the dataset names but that is not
            installed: naming its ``dataset.json``), one registered for another family than
            the dataset's (unless its config names it), or an option it does not take.
    """
    from bpb_core.registry import make_registry

    if horizon is not None and not 0 < horizon < math.inf:
        raise BadInput(f"--horizon: must be a positive finite number, got {horizon}")
    reg = registry if registry is not None else make_registry()
    given, names = dict(options or {}), dict(names or {})
    if simulator is None:
        family, spec, manifest = _made_with(files, reg)
        if manifest is not None:
            check_simulator(manifest, spec.name, reg, "; or choose one with --simulator")
        where = f"{f'{manifest}: ' if manifest else ''}config: simulator"
        return _built(reg, family, spec, where, given, names)
    if isinstance(simulator, str):
        spec = parse_spec(simulator, "--simulator")
        return _built(reg, _family_for(files, spec.name, reg), spec, "--simulator", given, names)
    name = reg.default_family()
    return Prepared(simulator, reg.scene_family(name), reg.origin("scene_family", name))


def _built(
    reg: Registry,
    family: SceneFamily,
    spec: SimulatorSpec,
    where: str,
    given: dict[str, Any],
    names: dict[str, str],
) -> Prepared:
    """``spec``'s simulator built with its options and ``given`` (which win), each option of the
    spec named in messages as ``where`` sets it (``--simulator 'pymunk:dt=0.5': dt``)."""
    names.update({k: f"{where} {spec.spec!r}: {k}" for k in spec.options if k not in given})
    made = reg.simulator(spec.name, {**spec.options, **given}, names=names)
    return Prepared(made, family, reg.origin("scene_family", family.name), names)


def _made_with(
    files: Sequence[Path], registry: Registry
) -> tuple[SceneFamily, SimulatorSpec, Path | None]:
    """The family of the dataset the first scene file belongs to, the simulator its config
    names with its options and its manifest (the default family, the simulator of its default
    config and ``None`` for loose scene files)."""
    folder = _dataset_of(files)
    if folder is not None:
        family = dataset_family(None, folder, registry)
        origin = registry.origin("scene_family", family.name)
        return family, dataset_simulator_spec(folder, family, origin), folder / MANIFEST
    family = registry.scene_family(registry.default_family())
    origin = registry.origin("scene_family", family.name)
    named = simulator_named(family, origin, loaded_config(family, origin, None))
    return family, parse_spec(named, "config: simulator"), None


def _dataset_of(files: Sequence[Path]) -> Path | None:
    """The dataset folder the first scene file belongs to (``None``: loose scene files)."""
    for folder in list(files[0].parents)[:3] if files else []:
        if (folder / MANIFEST).exists():  # a folder by that name is named as unreadable
            return folder
    return None


def _family_for(files: Sequence[Path], simulator: str, registry: Registry) -> SceneFamily:
    """The family that reads the scenes for ``--simulator``: their dataset's, when they belong
    to one, else the one the simulator is registered for (else the default one).

    Raises:
        BadInput: The simulator is registered for another family than the dataset's, and is
            not the one the dataset's config names (generation paired them).
    """
    simulates = registry.simulator_info(simulator).family
    folder = _dataset_of(files)
    if folder is None:
        return registry.scene_family(simulates or registry.default_family())
    family = dataset_family(None, folder, registry)
    if not simulates or simulates == family.name:
        return family
    made_with = dataset_simulator_spec(folder, family, registry.origin("scene_family", family.name))
    if made_with.name != simulator:
        raise BadInput(
            f"--simulator {simulator}: simulates {simulates} scenes, but {folder} holds "
            f"{family.name} scenes"
        )
    return family


def simulate_paths(
    paths: Iterable[str | Path],
    *,
    horizon: float | None = None,
    simulator: str | Simulator | None = None,
    stability: bool = False,
    registry: Registry | None = None,
    options: Mapping[str, Any] | None = None,
    names: Mapping[str, str] | None = None,
) -> Iterator[GroundTruth]:
    """Simulate every scene named by ``paths`` and yield their final states in input order.

    Args:
        paths: ``init.json``/``final.json`` files, scene folders or dataset folders.
        horizon: Override every scene's own horizon.
        simulator: A registered simulator name, a simulator object, or ``None`` for the one
            the scenes' dataset was made with (the default family's for loose files).
        stability: Also compute the stability annotation of each scene.
        registry: Registry to look the name up in (default: installed plugins).
        options: Options for the simulator (``dt`` for ``pymunk``, ``precision`` for analytic).
        names: How the caller's user sets each option (``{"dt": "--dt"}``), for messages
            (default: as the simulator takes it).

    Raises:
        BadInput: A path does not exist or a scene file is invalid (file and field named).
    """
    files = scene_files(paths)
    job = prepare(horizon, simulator, registry, options, files, names)
    for path in files:
        scene = read_model(path, job.family.scene_model, _special_data(str(path)))
        with _naming(path, job.names):
            truth = simulate_scene(
                scene, job.simulator, job.family, horizon, stability=stability, origin=job.origin
            )
        yield truth


_JOB: tuple[Prepared, float | None, bool] | None = None  # set before forking workers
PARALLEL_MIN = 256  # below this many scenes, worker start-up costs more than it saves


def simulate_lines(
    paths: Iterable[str | Path],
    *,
    horizon: float | None = None,
    simulator: str | Simulator | None = None,
    stability: bool = False,
    registry: Registry | None = None,
    options: Mapping[str, Any] | None = None,
    workers: int = 0,
    names: Mapping[str, str] | None = None,
) -> Iterator[str]:
    """Like :func:`simulate_paths` but yields each ``final.json`` as one JSON line, in input
    order, using ``workers`` processes (0: all cores when there are at least
    :data:`PARALLEL_MIN` scenes; 1: this process only).

    Workers are forked (POSIX only) and inherit the simulator, and what the first part of the
    scenes, simulated here before they start, loaded; elsewhere this runs in-process.
    """
    for block in simulate_blocks(
        paths,
        horizon=horizon,
        simulator=simulator,
        stability=stability,
        registry=registry,
        options=options,
        workers=workers,
        names=names,
    ):
        yield from block.decode().split("\n")[:-1]  # JSON text holds no newline


def simulate_blocks(
    paths: Iterable[str | Path],
    *,
    horizon: float | None = None,
    simulator: str | Simulator | None = None,
    stability: bool = False,
    registry: Registry | None = None,
    options: Mapping[str, Any] | None = None,
    workers: int = 0,
    names: Mapping[str, str] | None = None,
) -> Iterator[bytes]:
    """:func:`simulate_lines`'s lines in blocks of up to :data:`CHUNK` lines, as they are to
    be written: UTF-8, each line ended by a newline (what ``bpb simulate`` prints). A bad
    file's error is raised after the block of the lines before it."""
    global _JOB
    if workers < 0:
        raise BadInput(f"--workers: must be 0 (automatic) or more, got {workers}")
    check_workers(workers, least=0)
    try:
        files = _scene_names(paths, ahead=True)
        job = prepare(horizon, simulator, registry, options, [Path(f) for f in files[:1]], names)
        count = _worker_count(workers, len(files))
        _JOB = (job, horizon, stability)
        if count > 1:  # forked workers share the pipes but not what one of them read
            for name in files:
                _special_data(name)
        if count <= 1:
            for at in range(0, len(files), CHUNK):
                yield from _emit(_lines(files[at : at + CHUNK]))
            return
        import multiprocessing

        parts = _split(files, count)
        yield from _emit(_lines(parts[0]))  # the workers inherit what it loaded (or built: once)
        fork = multiprocessing.get_context("fork")
        with started_pool(lambda: fork.Pool(count, initializer=worker_signals)) as pool:
            for result in pool.imap(_lines, parts[1:]):
                yield from _emit(result)
    finally:
        _AHEAD.clear()  # what was read ahead for files a bad one stopped short of


CHUNK = 512  # scenes handed to a family's batch path at once


def _split(files: Sequence[str], count: int) -> list[Sequence[str]]:
    size = max(16, min(CHUNK, len(files) // (4 * count) or 1))
    return [files[i : i + size] for i in range(0, len(files), size)]


def _emit(result: tuple[list[str] | bytes, BadInput | None]) -> Iterator[bytes]:
    lines, error = result
    if lines:
        yield lines + b"\n" if isinstance(lines, bytes) else ("\n".join(lines) + "\n").encode()
    if error is not None:
        raise error


def _lines(files: Sequence[str]) -> tuple[list[str] | bytes, BadInput | None]:
    """JSON lines of ``files``: the family's batch path (:class:`WritesTruthLines`) when it has
    one for this simulator and no stability is asked, else one ground truth model per scene.
    A bad file ends the chunk: the lines before it come back with the error. The lines come
    as a list, or as the family's block of them all (bytes, joined by newlines)."""
    from bpb_core.capabilities import WritesTruthLines

    assert _JOB is not None
    job, horizon, stability = _JOB
    texts: list[bytes] = []  # the ordinary path takes these bytes: a pipe is read only once
    if not stability and isinstance(job.family, WritesTruthLines):
        texts = _read_all(files)
        try:
            fast = _truth_lines(job, job.family, texts, horizon) if texts else []
        except PluginBug:
            raise
        except BpbError:  # e.g. an event cap overrun: the ordinary path below names the file
            fast = None
        if fast is not None:
            return _fill(files, fast, texts)
    return _fill(files, [], texts)


def _truth_lines(
    job: Prepared, family: WritesTruthLines, texts: Sequence[bytes], horizon: float | None
) -> list[str | None] | bytes | None:
    """The family's ``truth_lines`` of ``texts``, checked: ``None``, a list with one line
    (``str``) or ``None`` per text, since each line is paired with its file by position, or a
    block (UTF-8 bytes) of one line per text joined by newlines.

    Raises:
        PluginBug: The family raised or returned something else, naming its plugin.
    """
    what = f"scene family {job.family.name!r}: truth_lines()"
    with blamed(job.origin, what):
        lines = family.truth_lines(texts, job.simulator, horizon)
    if lines is None:
        return None
    if isinstance(lines, bytes):
        return _checked_block(lines, len(texts), f"{job.origin}: {what}")
    if not isinstance(lines, list) or len(lines) != len(texts):
        got = f"a list of {len(lines)}" if isinstance(lines, list) else type(lines).__name__
        raise PluginBug(
            f"{job.origin}: {what} returned {got} for {len(texts)} scene files; expected a list "
            "with one line or None per file, or a block of one line per file"
        )
    wrong = next((line for line in lines if line is not None and not isinstance(line, str)), None)
    if wrong is not None:
        raise PluginBug(
            f"{job.origin}: {what} returned a list holding {type(wrong).__name__}; expected a "
            "JSON line (str) or None per file"
        )
    return lines


def _checked_block(block: bytes, files: int, who: str) -> bytes:
    """``block`` when it holds ``files`` lines of UTF-8 (non-ASCII is decoded to check)."""
    lines = block.count(b"\n") + 1
    if lines != files:
        raise PluginBug(
            f"{who} returned a block of {lines} lines for {files} scene files; expected one "
            "line per file"
        )
    if not block.isascii():
        try:
            block.decode()
        except UnicodeDecodeError as exc:
            raise PluginBug(f"{who} returned a block that is not UTF-8 ({exc.reason})") from None
    return block


def _read_all(files: Sequence[str]) -> list[bytes]:
    """The bytes of ``files`` up to the first that cannot be read (the ordinary path reads it
    again and names the error): ``os.open`` and ``os.read``, no file object per scene."""
    texts: list[bytes] = []
    flags = os.O_RDONLY | getattr(os, "O_BINARY", 0)
    ahead = _AHEAD
    for path in files:
        read = ahead.pop(path, None)
        if read is not None:
            texts.append(read)
            continue
        if path in _SPECIAL:
            data = _special_data(path)
            if data is None:
                break
            texts.append(data)
            continue
        try:
            fd = os.open(path, flags)
        except OSError:
            break
        try:
            data = os.read(fd, _READ)
            if len(data) == _READ:  # else a regular file read to its end
                while more := os.read(fd, _READ):
                    data += more
        except OSError:
            break
        finally:
            os.close(fd)
        texts.append(data)
    return texts


_READ = 1 << 16


def _special_data(path: str) -> bytes | None:
    """The bytes of ``path`` when it is one of :data:`_SPECIAL`, read to its end the first time
    its device and inode are met and kept (:data:`_PIPED`); ``None`` for a regular file or one
    that cannot be read (the reader reads it again and names the error)."""
    if path not in _SPECIAL:
        return None
    try:
        info = os.stat(path)  # not open: a named pipe's open waits for a writer
        key = (info.st_dev, info.st_ino)
        if key not in _PIPED:
            with open(path, "rb", buffering=0) as file:
                _PIPED[key] = b"".join(iter(lambda: file.read(_READ), b""))
        return _PIPED[key]
    except OSError:
        return None


def _fill(
    files: Sequence[str], fast: list[str | None] | bytes, texts: Sequence[bytes]
) -> tuple[list[str] | bytes, BadInput | None]:
    """The fast lines, with the files the fast path left (``None``) and those after the texts
    it got done the ordinary way, from the bytes already read (``texts``, a prefix of
    ``files``) where there are some; a bad file ends the chunk."""
    if isinstance(fast, bytes):  # a line for every text read
        if len(texts) == len(files):
            return fast, None
        split: list[str | None] = [*fast.decode().split("\n")]
        fast = split
    if len(fast) == len(files) and None not in fast:  # the usual case: every file taken
        return fast, None  # type: ignore[return-value]  # no None in it
    lines: list[str] = []
    for index, path in enumerate(files):
        line = fast[index] if index < len(fast) else None
        if line is None:
            try:
                line = _line(path, texts[index] if index < len(texts) else None)
            except BadInput as exc:
                return lines, exc
        lines.append(line)
    return lines, None


def _worker_count(workers: int, scenes: int) -> int:
    import multiprocessing

    if workers == 1 or "fork" not in multiprocessing.get_all_start_methods():
        return 1
    if workers > 1:
        return workers
    return (os.cpu_count() or 1) if scenes >= PARALLEL_MIN else 1


def _line(name: str, data: bytes | None = None) -> str:
    """The ``final.json`` line of the scene file ``name`` (``data``: its bytes, if read)."""
    assert _JOB is not None
    job, horizon, stability = _JOB
    path = Path(name)
    if data is None:
        data = _AHEAD.pop(name, None)
    if data is None:
        data = _special_data(name)
    scene = read_model(path, job.family.scene_model, data)
    with _naming(path, job.names):
        truth = simulate_scene(
            scene, job.simulator, job.family, horizon, stability=stability, origin=job.origin
        )
    return truth.model_dump_json()


@contextlib.contextmanager
def _naming(path: Path, names: Mapping[str, str]) -> Iterator[None]:
    """Turn a simulator's own error on a scene (an event cap overrun, a step budget) into bad
    input naming the scene file, and the option it is about as ``names`` do (``--dt``); a
    plugin's bug stays one, naming the plugin."""
    try:
        yield
    except PluginBug:
        raise
    except BadInput as exc:
        if str(path) in str(exc):
            raise
        raise BadInput(f"{path}: {exc.naming(names)}") from None
    except BpbError as exc:
        raise BadInput(f"{path}: {exc.naming(names)}") from None
