"""What a partial or mixed set of runs makes a report say: never a finding from missing data,
never one leaderboard over two datasets."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from bpb_core.errors import BadInput
from bpb_core.registry import make_registry
from bpb_core.report.build import Completeness, build_report, unasked
from bpb_core.report.sections import headline_cells
from support.inprocess import Done, bpb
from support.reports_fixture import all_answers, oracle_answer, write_dataset, write_run


@pytest.fixture
def bpb_report(
    capfd: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> Callable[..., Done]:
    """``bpb report RUNS ARGS`` in this process, ``columns`` wide when given; ``check``: it
    must exit 0."""

    def report(runs: Path, *args: str, columns: str | None = None, check: bool = False) -> Done:
        with monkeypatch.context() as environment:
            if columns is not None:
                environment.setenv("COLUMNS", columns)
            done = bpb(capfd, "report", str(runs), *args)
        assert not check or done.returncode == 0, done.stderr
        return done

    return report


def _stopped_run(root: Path, data: Path) -> Path:
    """An oracle-perfect model stopped after horizon 1: nothing answered at horizon 2."""
    answers = {key: value for key, value in all_answers(oracle_answer).items() if key[0][1] == "1"}
    return write_run(root / "runs" / "stopped", "litellm:stopped", data, answers)


def test_a_stopped_run_does_not_fall_with_horizon(tmp_path: Path) -> None:
    data = write_dataset(tmp_path / "data")
    _stopped_run(tmp_path, data)
    report = build_report(tmp_path / "runs", n_boot=20, registry=make_registry())
    acc = report.tables["accuracy"].set_index(["task", "horizon"])
    # strict: the unanswered horizon reads 0%, but is marked short ...
    assert acc.loc[("q1", 2.0), "accuracy"] == 0.0 and acc.loc[("q1", 2.0), "level"] == "short"
    assert acc.loc[("q1", 1.0), "level"] == "full"
    # ... and no leaderboard or interval ranks the run on it
    for name in ("leaderboard", "leaderboard_answered", "summary"):
        row = report.tables[name].iloc[0]
        assert row[["q1", "q2", "q3", "total"]].isna().all(), name
        assert row["short"] == "q1, q2, q3"
    assert report.tables["bootstrap"]["estimate"].isna().all()
    summary = report.summary_json()
    assert summary["incomplete"] == {"stopped": "incomplete: 6 calls never sent, re-run to resume"}
    cells = {(c["task"], c["horizon"]): c for c in summary["completeness"]}
    assert cells[("q3", 2.0)]["level"] == "short" and cells[("q3", 2.0)]["answered"] == 0


def test_include_incomplete_keeps_the_scores_but_still_marks_them(tmp_path: Path) -> None:
    data = write_dataset(tmp_path / "data")
    _stopped_run(tmp_path, data)
    rule = Completeness(include_incomplete=True)
    report = build_report(tmp_path / "runs", n_boot=20, completeness=rule)
    row = report.tables["leaderboard_answered"].iloc[0]
    assert row["total"] == 1.0 and row["short"] == "q1, q2, q3"


def test_runs_on_two_datasets_are_two_sections_never_one_leaderboard(tmp_path: Path) -> None:
    first, second = write_dataset(tmp_path / "d1"), write_dataset(tmp_path / "d2")
    runs = tmp_path / "runs"
    write_run(runs / "a", "baseline:oracle", first, all_answers(oracle_answer))
    write_run(runs / "b", "baseline:oracle", second, all_answers(oracle_answer))
    report = build_report(runs, tmp_path / "out", n_boot=20, gallery_size=0)
    assert [p.results.runs[0].label for p in report.parts] == ["a", "b"]
    assert all(len(p.tables["leaderboard"]) == 1 for p in report.parts)
    with pytest.raises(BadInput, match="2 datasets"):
        _ = report.tables
    summary = json.loads(json.dumps(report.summary_json(), default=str))
    assert "leaderboard" not in summary and len(summary["datasets"]) == 2
    page = (tmp_path / "out" / "report.html").read_text()
    assert "answered 2 different" in page and page.count("<h2>Dataset ") == 2
    tables = sorted(p.name for p in (tmp_path / "out" / "tables").glob("*leaderboard.md"))
    assert len(tables) == 2  # one per dataset, prefixed with its short id


def test_markdown_and_booktabs_exports_show_the_same_cells(runs: Path, tmp_path: Path) -> None:
    build_report(runs, tmp_path / "out", n_boot=20, gallery_size=0)
    tables = tmp_path / "out" / "tables"
    md = (tables / "by_horizon.md").read_text().splitlines()
    assert md[0].startswith("| run | task | h1 | h2 | mean |") and md[1].startswith("| :---")
    model_q2 = next(line for line in md if line.startswith("| litellm_model | q2"))
    assert model_q2 == "| litellm_model | q2 | 50.0% | left out (50.0%) | left out |"
    tex = (tables / "leaderboard.tex").read_text()
    for rule in ("\\toprule", "\\midrule", "\\bottomrule", "\\caption{"):
        assert tex.count(rule) == 1, rule
    assert "baseline\\_stasis (baseline) & 100.0\\% & 87.5\\%" in tex
    assert "%" not in tex.replace("\\%", "")  # no bare % would comment the rest of a line out
    assert (tables / "q1_metrics.tex").is_file() and (tables / "q1_metrics.md").is_file()


def test_json_carries_by_horizon_completeness_usage_and_confusion(runs: Path) -> None:
    summary = build_report(runs, n_boot=20).summary_json()
    rows = {(r["run"], r["task"], r["horizon"]): r for r in summary["by_horizon"]}
    cell = rows[("litellm_model", "q1", 1.0)]
    assert cell["accuracy_strict"] == 0.5 and cell["accuracy_answered"] == 1.0
    assert cell["completeness"] == 0.5 and cell["level"] == "short"
    assert {u["run"] for u in summary["usage"]} == {
        "baseline_oracle",
        "baseline_stasis",
        "litellm_model",
    }
    assert {"q1_confusion", "q2_confusion"} <= set(summary["diagnostics"])
    assert summary["completeness_rule"] == {"min_complete": 0.9, "include_incomplete": False}


def test_a_run_still_running_is_reported_as_running_not_as_to_resume(tmp_path: Path) -> None:
    # A report taken while bpb run was still going said "6 calls never sent, re-run to
    # resume": re-running is refused while the run holds the folder.
    data = write_dataset(tmp_path / "data")
    run_dir = _stopped_run(tmp_path, data)
    holder = subprocess.Popen(  # another process holding the folder as bpb run does
        [
            sys.executable,
            "-c",
            "import sys, pathlib\n"
            "from bpb_core.runner.manifest import run_lock\n"
            "with run_lock(pathlib.Path(sys.argv[1])):\n"
            "    print('held', flush=True); sys.stdin.read()\n",
            str(run_dir),
        ],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline() == "held\n"
        running = build_report(tmp_path / "runs", n_boot=20).summary_json()["incomplete"]
    finally:
        holder.communicate("")
    assert running == {
        "stopped": f"still running (bpb run pid {holder.pid}): 6 calls not answered yet; "
        "report again when it ends"
    }
    ended = build_report(tmp_path / "runs", n_boot=20).summary_json()["incomplete"]
    assert ended == {"stopped": "incomplete: 6 calls never sent, re-run to resume"}


def test_a_folder_named_run_lock_is_no_run_running(
    tmp_path: Path, bpb_report: Callable[..., Done]
) -> None:
    # bpb report exited 3 ("internal error: IsADirectoryError") reading the pid in run.lock
    data = write_dataset(tmp_path / "data")
    (_stopped_run(tmp_path, data) / "run.lock").mkdir()
    summary = json.loads(bpb_report(tmp_path / "runs", "--json", check=True).stdout)
    assert summary["incomplete"] == {"stopped": "incomplete: 6 calls never sent, re-run to resume"}


def test_a_task_a_run_was_not_asked_is_not_called_too_incomplete(tmp_path: Path) -> None:
    # A run asked q1 only read "left out" (too incomplete) under q2, q3 and the suite, in the
    # leaderboard and its chart, while its own "left out" column said nothing was.
    data = write_dataset(tmp_path / "data")
    q1 = {k: v for k, v in all_answers(oracle_answer).items() if k[1] == "q1"}
    write_run(tmp_path / "runs" / "q1only", "litellm:q1only", data, q1, tasks=("q1",))
    _stopped_run(tmp_path, data)
    report = build_report(tmp_path / "runs", n_boot=20)
    part = report.parts[0]
    head, rows = headline_cells(part, Completeness())
    cells = {str(r[0].text): dict(zip(head, (c.text for c in r), strict=True)) for _, r in rows}
    suite = part.results.suites[0].name
    assert cells["q1only"]["q1"] == "100.0%"
    assert [cells["q1only"][c] for c in ("q2", "q3", suite, "left out")] == ["–"] * 4
    assert [cells["stopped"][c] for c in ("q1", "q2", suite)] == ["left out"] * 3
    assert unasked(part, ["q1", "q2", suite]) == {"q1": [], "q2": ["q1only"], suite: ["q1only"]}


def test_calls_the_api_refused_are_not_called_infrastructure_failures(tmp_path: Path) -> None:
    # A 400 (say, a model that takes no images) was counted among the calls that "failed on
    # infrastructure, re-run to resume": re-running sends the same request and fails again.
    data = write_dataset(tmp_path / "data")
    answers: dict[tuple[str, str], dict[str, Any] | None] = dict(all_answers(oracle_answer))
    keys = sorted(answers)
    for key in keys[:2]:
        answers[key] = {"status": "api_error", "error": "RequestRejected: 400 image input"}
    answers[keys[2]] = {"status": "api_error", "error": "ServerError: 503 try later"}
    answers[keys[3]] = {"status": "missing"}
    write_run(tmp_path / "runs" / "mixed", "litellm:mixed", data, answers)
    for key in keys[2:4]:
        answers[key] = all_answers(oracle_answer)[key]
    write_run(tmp_path / "runs" / "refused", "litellm:refused", data, answers)
    lines = build_report(tmp_path / "runs", n_boot=20).summary_json()["incomplete"]
    refused = (
        "2 calls refused by the API (a 4xx: re-running sends the same request; the error is "
        "in each answer file)"
    )
    assert lines == {
        "mixed": "incomplete: 1 call failed on infrastructure and 1 call never sent, re-run to "
        f"resume; {refused}",
        "refused": f"incomplete: {refused}",
    }


def test_a_run_with_no_answer_at_all_is_listed_not_dropped(tmp_path: Path) -> None:
    data = write_dataset(tmp_path / "data")
    write_run(tmp_path / "runs" / "nothing", "litellm:none", data, {})
    _stopped_run(tmp_path, data)
    report = build_report(tmp_path / "runs", tmp_path / "out", n_boot=20, gallery_size=0)
    board = report.tables["leaderboard_answered"].set_index("run")
    assert board.loc["nothing", "completeness"] == 0.0 and board.loc["nothing", "short"]
    assert board.loc["nothing", ["q1", "total"]].isna().all()
    assert (tmp_path / "out" / "charts" / "accuracy_by_horizon.png").stat().st_size > 0


def test_diagnostic_charts_leave_out_too_incomplete_runs_and_say_so(
    runs: Path, tmp_path: Path
) -> None:
    report = build_report(runs, tmp_path / "out", n_boot=20, gallery_size=0)
    assert "litellm_model" in set(report.tables["stasis"]["run"])  # the table keeps it
    page = (tmp_path / "out" / "report.html").read_text()
    stasis = page[page.index("<h3>Stasis index</h3>") :]
    assert stasis.index("left out as too incomplete: litellm_model") < stasis.index("<h2>")


def test_a_report_without_baselines_says_the_floors_are_missing(tmp_path: Path) -> None:
    data = write_dataset(tmp_path / "data")
    _stopped_run(tmp_path, data)
    build_report(tmp_path / "runs", tmp_path / "out", n_boot=20, gallery_size=0)
    page = (tmp_path / "out" / "report.html").read_text()
    assert "No baseline ran on this dataset" in page and "--adapter baseline:stasis" in page


@pytest.mark.parametrize(
    ("field", "value"),
    [("scene_id", "h1_0000"), ("task", "q1"), ("epoch", 3), ("adapter", "baseline:stasis")],
)
def test_an_answer_file_copied_in_from_elsewhere_is_refused_not_scored(
    bpb_report: Callable[..., Done], runs: Path, field: str, value: object
) -> None:
    # An answer file copied from another scene (or task, epoch, run) was scored against the
    # truth of the scene whose folder it sat in: the oracle read 87.5% on q3, without a word.
    target = runs / "baseline_oracle" / "h1" / "scene_0001" / "q3.json"
    record = json.loads(target.read_text())
    target.write_text(json.dumps(record | {field: value}))
    done = bpb_report(runs, "--json")
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.strip().splitlines() == [
        f"error: {target}: {field} is {value!r}, but a file here holds the answer of h1_0001, "
        "task q3, epoch 1 by baseline:oracle (copied in from another scene, task or run?)"
    ]


def test_runs_asked_with_another_input_mode_or_chain_of_thought_are_flagged(
    bpb_report: Callable[..., Done],
    tmp_path: Path,
) -> None:
    # A run on the scene's state and one without chain of thought were ranked beside image runs
    # in one leaderboard, with nothing in the terminal, the HTML or --json to say so.
    data = write_dataset(tmp_path / "data")
    runs = tmp_path / "runs"
    answers = all_answers(oracle_answer)
    write_run(runs / "image", "litellm:m", data, answers)
    write_run(runs / "image_too", "litellm:n", data, answers)
    state = {key: value | {"input_mode": "state"} for key, value in answers.items() if value}
    write_run(runs / "state", "litellm:m", data, state)
    no_cot = {key: value | {"cot": False} for key, value in answers.items() if value}
    write_run(runs / "no_cot", "litellm:m", data, no_cot)
    expected = (
        "The runs were asked under different conditions (input mode: image (image, image_too, "
        "no_cot), state (state); chain of thought on q1: off (no_cot), on (image, image_too, "
        "state); chain of thought on q2: off (no_cot), on (image, image_too, state)): a gap "
        "between them may come from the conditions, not the models; rank only runs asked alike."
    )
    out = str(tmp_path / "out")
    shown = bpb_report(runs, "--out", out, "--bootstrap", "10", columns="1000", check=True).stdout
    assert expected in shown.splitlines()
    assert expected in (tmp_path / "out" / "report.html").read_text()
    summary = json.loads(bpb_report(runs, "--json", check=True).stdout)
    assert summary["different_conditions"] == expected
    write_run(tmp_path / "alike" / "a", "litellm:m", data, answers)
    write_run(tmp_path / "alike" / "b", "litellm:n", data, answers)
    alike = build_report(tmp_path / "alike", n_boot=10).summary_json()
    assert alike["different_conditions"] is None


def test_a_run_whose_answers_could_not_be_parsed_is_said_so(
    bpb_report: Callable[..., Done], tmp_path: Path
) -> None:
    # A run whose every answer was a parse error read complete 100%, 0.0% on every task with a
    # 0.0%-0.0% interval, below stasis, and nothing said the scores came from unreadable replies.
    data = write_dataset(tmp_path / "data")
    runs = tmp_path / "runs"
    answers = all_answers(oracle_answer)
    unreadable = {"status": "parse_error", "answer": None, "error": "no JSON"}
    write_run(runs / "unread", "litellm:m", data, {key: unreadable for key in answers})
    one = dict(answers) | {next(iter(answers)): unreadable}
    write_run(runs / "one_bad", "litellm:n", data, one)  # 1 of 4 answers: no line
    line = (
        "unread: answers that could not be parsed (q1 4 of 4, q2 4 of 4, q3 4 of 4) are scored "
        "wrong: those scores say how the run answered, not what it knows; see the failure gallery"
    )
    out = str(tmp_path / "out")
    shown = bpb_report(runs, "--out", out, "--bootstrap", "10", columns="1000", check=True).stdout
    assert line in shown.splitlines() and "one_bad:" not in shown
    assert line in (tmp_path / "out" / "report.html").read_text()
    summary = json.loads(bpb_report(runs, "--json", check=True).stdout)
    assert summary["unparsed"] == {"unread": line.removeprefix("unread: ")}


def test_an_ok_answer_file_without_an_answer_is_refused_not_scored_wrong(
    bpb_report: Callable[..., Done], runs: Path
) -> None:
    # A file saying ok with answer null (bpb writes an ok with its parsed answer) was scored
    # wrong as if answered: the oracle read 0% on q1 at complete 100%, with no word.
    target = runs / "baseline_oracle" / "h2" / "scene_0001" / "q1.json"
    target.write_text(json.dumps(json.loads(target.read_text()) | {"answer": None}))
    done = bpb_report(runs, "--json")
    assert done.returncode == 2 and done.stdout == ""
    assert done.stderr.strip().splitlines() == [
        f"error: {target}: status is 'ok' but answer is null: an ok answer file holds one"
    ]


def test_answer_files_outside_the_runs_selection_are_said_to_be_left_out(
    bpb_report: Callable[..., Done], runs: Path
) -> None:
    # Answer files the run's selection does not ask for (a scene outside its horizons, a task
    # it was not asked, an epoch past its --epochs: put there by hand or left by another run)
    # were left out of every figure without a word.
    run = runs / "baseline_oracle"
    source = run / "h1" / "scene_0001" / "q3.json"
    record = json.loads(source.read_text())
    (run / "h1" / "scene_0001" / "q3.e2.json").write_text(json.dumps(record | {"epoch": 2}))
    (run / "h1" / "scene_0001" / "firsthit.json").write_text(json.dumps(record | {"task": "x"}))
    (run / "h9" / "scene_0000").mkdir(parents=True)
    (run / "h9" / "scene_0000" / "q3.json").write_text(source.read_text())
    done = bpb_report(runs, "--json", check=True)
    assert done.stderr.strip().splitlines() == [
        f"warning: {run}: 3 answer files outside the run's selection (the scenes, tasks and "
        f"epochs of its run.json), e.g. {source.parent / 'firsthit.json'}: left out of the report"
    ]
    board = {row["run"]: row for row in json.loads(done.stdout)["leaderboard"]}
    assert board["baseline_oracle"]["total"] == 1.0 and board["baseline_oracle"]["expected"] == 12
    for stray in (
        "h1/scene_0001/q3.e2.json",
        "h1/scene_0001/firsthit.json",
        "h9/scene_0000/q3.json",
    ):
        (run / stray).unlink()
    assert bpb_report(runs, "--json", check=True).stderr == ""


@pytest.mark.parametrize(
    ("task", "edit", "field"),
    [
        ("q1", lambda a: a["answers"][2].update(answer="yes"), "answers.2.answer"),
        ("q1", lambda a: a.update(answers="TFFFFF"), "answers"),
        ("q3", lambda a: a["predictions"][0].update(pos="0.5, 0.5"), "predictions.0.pos"),
    ],
)
def test_a_recorded_answer_with_a_wrong_typed_field_is_refused_not_scored_wrong(
    bpb_report: Callable[..., Done], runs: Path, task: str, edit: Any, field: str
) -> None:
    # An answer file edited so a field held the wrong type (a label "yes", a string for a list)
    # was scored as the model's wrong answer: the oracle read under 100% with no word.
    target = runs / "baseline_oracle" / "h2" / "scene_0001" / f"{task}.json"
    record = json.loads(target.read_text())
    edit(record["answer"])
    target.write_text(json.dumps(record))
    done = bpb_report(runs, "--json")
    assert done.returncode == 2 and done.stdout == ""
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {target}: answer: {task}: {field}: ")
    assert lines[0].endswith(
        "(a damaged answer file: bpb records only answers the task's parser accepted)"
    )


def test_a_well_typed_wrong_answer_is_still_scored_wrong_and_a_parse_error_unparsed(
    bpb_report: Callable[..., Done],
    runs: Path,
) -> None:
    target = runs / "baseline_oracle" / "h2" / "scene_0001" / "q2.json"
    record = json.loads(target.read_text())
    for label in record["answer"]["answers"]:
        label["answer"] = "F" if label["answer"] == "T" else "T"  # every wall wrong, well typed
    target.write_text(json.dumps(record))
    summary = json.loads(bpb_report(runs, "--json", check=True).stdout)
    board = {row["run"]: row for row in summary["leaderboard"]}
    assert board["baseline_oracle"]["q2"] == 0.75 and board["baseline_oracle"]["completeness"] == 1
    usage = {row["run"]: row for row in summary["usage"]}
    assert usage["litellm_model"]["parse_error"] == 1  # its h1_0001 q2 reply did not parse
