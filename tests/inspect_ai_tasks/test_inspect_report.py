"""``bpb report`` and ``load_results`` read Inspect logs of bpb tasks as runs, so one report
compares a model run with ``inspect eval bpb/...`` and one run with ``bpb run``."""

from __future__ import annotations

import functools
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest
from inspect_ai import Task, eval as inspect_eval
from inspect_ai.dataset import Sample
from inspect_ai.scorer import match

from bpb_core import RunOptions, leaderboard, load_results, run_eval
from support.inprocess import Done, bpb
from support.inspect_models import ExampleAdapter


@pytest.fixture
def run_bpb(site: Path, capfd: pytest.CaptureFixture[str]) -> Callable[..., Done]:
    """``bpb ARGS`` in this process, ``site`` first on ``sys.path`` (conftest's ``run_bpb``
    runs the console script)."""
    return functools.partial(bpb, capfd, site=site)


@pytest.fixture
def logs(small_dataset: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    import support.inspect_models  # noqa: F401 (registers bpbtest/example)

    monkeypatch.setenv("INSPECT_DISPLAY", "none")
    monkeypatch.setenv("BPB_CACHE_DIR", str(tmp_path / "cache"))
    out = tmp_path / "logs"
    for name in ("bpb/q1", "bpb/q2"):  # two logs of one model: one run with both tasks
        inspect_eval(
            name, model="bpbtest/example", task_args={"data": str(small_dataset)}, log_dir=str(out)
        )
    return out


def test_inspect_logs_score_like_the_same_replies_in_bpb(
    logs: Path, small_dataset: Path, tmp_path: Path
) -> None:
    options = RunOptions(tasks=("q1", "q2"))
    run_eval(small_dataset, ExampleAdapter(), tmp_path / "runs" / "example", options)
    results = load_results([logs, tmp_path / "runs"])
    board = leaderboard(results).set_index("adapter")
    assert sorted(board.index) == ["example", "inspect:bpbtest/example"]
    assert board.loc["inspect:bpbtest/example", "completeness"] == 1.0
    for task in ("q1", "q2"):
        by_run = board[task]
        assert by_run["inspect:bpbtest/example"] == pytest.approx(by_run["example"], abs=1e-12)
    units = results.units
    assert len(units[units["adapter"] == "inspect:bpbtest/example"]) == 6 * (6 + 4)


@pytest.mark.slow
def test_bpb_report_on_logs_and_a_foreign_log(
    logs: Path,
    tmp_path: Path,
    run_bpb: Callable[..., Done],
) -> None:
    done = run_bpb("report", str(logs), "--out", str(tmp_path / "report"))
    assert done.returncode == 0, done.stderr
    assert "inspect_bpbtest_example" in done.stdout
    assert (tmp_path / "report" / "report.html").is_file()
    other = Task(dataset=[Sample(input="Say x", target="x")], scorer=match())
    (log,) = inspect_eval(other, model="bpbtest/example", log_dir=str(tmp_path / "other"))
    assert log.status == "success"
    bad = run_bpb("report", log.location)
    assert bad.returncode == 2
    assert bad.stderr.strip().endswith("not an Inspect log of a bpb task (inspect eval bpb/...)")
    assert len(bad.stderr.strip().splitlines()) == 1


def test_a_log_with_failed_calls_reads_as_api_errors(
    small_dataset: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A sample whose model call failed has an output with no choices; reading the log raised
    IndexError (``ModelOutput.stop_reason``) instead of counting the calls as failed."""
    import support.inspect_models  # noqa: F401 (registers bpbtest/down)

    monkeypatch.setenv("INSPECT_DISPLAY", "none")
    monkeypatch.setenv("BPB_CACHE_DIR", str(tmp_path / "cache"))
    (log,) = inspect_eval(
        "bpb/q2",
        model="bpbtest/down",
        task_args={"data": str(small_dataset)},
        log_dir=str(tmp_path / "logs"),
        fail_on_error=False,
        retry_on_error=0,
    )
    assert log.samples and all(sample.error is not None for sample in log.samples)
    units = load_results([tmp_path / "logs"]).units
    assert set(units["status"]) == {"api_error"}
    assert len(units) == 6 * 4
    assert not units["correct"].any()


def test_logs_read_by_two_callers_at_once(logs: Path) -> None:
    """Each reading emptied the logs' cache folder and rewrote it: a second reader at the same
    time (two threads, two bpb report) hit FileNotFoundError in the folder being rebuilt."""
    import threading

    errors: list[BaseException] = []
    boards: list[list[str]] = []

    def read() -> None:
        for _ in range(4):
            try:
                boards.append(sorted(leaderboard(load_results([logs]))["adapter"]))
            except BaseException as exc:  # collected for the assertion
                errors.append(exc)

    readers = [threading.Thread(target=read) for _ in range(3)]
    for reader in readers:
        reader.start()
    for reader in readers:
        reader.join()
    assert not errors
    assert boards == [["inspect:bpbtest/example"]] * 12


HOLDER = """
import sys
from pathlib import Path
from bpb_core.registry import make_registry
from bpb_core.web.viewer import Viewer

viewer = Viewer.load([Path(sys.argv[1])], make_registry())
print(viewer.results.runs[0].path, flush=True)
sys.stdin.readline()  # meanwhile another process reads a newer state of the logs
answers = list(viewer.results.runs[0].path.rglob("q1.json"))
print(len(answers), sum(len(p.read_text()) > 0 for p in answers), flush=True)
"""


def _cached(cache: Path) -> list[str]:
    return sorted(p.name for p in (cache / "inspect").iterdir() if not p.name.startswith("."))


def test_each_new_log_replaces_the_cache_folder_unless_another_process_holds_it(
    small_dataset: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Each reading of a log folder that had gained a log left one more cache folder (named by
    the logs' state), so evaluations in a row accumulated them. A newer state now replaces the
    older ones, except a folder another process still reads (bpb view, say): it stays until that
    process lets go, and goes at the next reading."""
    import sys

    import support.inspect_models  # noqa: F401 (registers bpbtest/example)

    cache = tmp_path / "cache"
    monkeypatch.setenv("INSPECT_DISPLAY", "none")
    monkeypatch.setenv("BPB_CACHE_DIR", str(cache))
    out = tmp_path / "logs"

    def evaluate(name: str) -> None:
        inspect_eval(
            name, model="bpbtest/example", task_args={"data": str(small_dataset)}, log_dir=str(out)
        )

    evaluate("bpb/q1")
    assert sorted(load_results([out]).tasks) == ["q1"]
    first = _cached(cache)
    assert len(first) == 1
    holder = subprocess.Popen(
        [sys.executable, "-c", HOLDER, str(out)],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    assert holder.stdout is not None and holder.stdin is not None
    held = Path(holder.stdout.readline().strip())
    assert held.parent.name == first[0]
    evaluate("bpb/q2")
    assert sorted(load_results([out]).tasks) == ["q1", "q2"]
    assert len(_cached(cache)) == 2 and first[0] in _cached(cache)  # still read by the holder
    reading, _ = holder.communicate("\n", timeout=120)
    assert holder.returncode == 0
    assert reading.split() == ["6", "6"]  # every answer file still there for the holder
    assert sorted(load_results([out]).tasks) == ["q1", "q2"]
    assert len(_cached(cache)) == 1 and first[0] not in _cached(cache)
    evaluate("bpb/q1")  # a third evaluation in a row: still one folder
    load_results([out])
    assert len(_cached(cache)) == 1
