"""`bpb report` through the real entry point, its files, and the HTML in headless Chromium."""

from __future__ import annotations

import functools
import json
import os
import re
import shutil
import subprocess
from collections.abc import Callable
from pathlib import Path

import pandas as pd
import pytest
from PIL import Image

from bpb_core.results import CALL_DTYPES, META_DTYPES
from bpb_core.scored_units import SCORER_INPUT, SCORER_OUTPUT
from bpb_tasks.q3.scorer import COLUMNS as Q3_COLUMNS
from support import inprocess
from support.inprocess import Done
from support.web_server import chromium

UNIT_DTYPES = {**META_DTYPES, **SCORER_INPUT, **Q3_COLUMNS, **SCORER_OUTPUT}

CHROMIUM_FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
]  # fmt: skip


@pytest.fixture
def bpb(capfd: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> Callable[..., Done]:
    """``bpb ARGS`` in this process, 160 columns wide."""
    monkeypatch.setenv("COLUMNS", "160")
    return functools.partial(inprocess.bpb, capfd)


@pytest.fixture(scope="module")
def report_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from support.reports_fixture import write_runs

    root = tmp_path_factory.mktemp("report")
    runs = write_runs(root)
    with pytest.MonkeyPatch.context() as monkeypatch, inprocess.streams() as capture:
        monkeypatch.setenv("COLUMNS", "160")
        args = ("report", str(runs), "--out", str(root / "out"), "--bootstrap", "200")
        done = inprocess.bpb(capture, *args)
    assert done.returncode == 0, done.stderr
    (root / "stdout.txt").write_text(done.stdout)
    return root


def test_terminal_tables_show_the_leaderboard_with_baselines_marked(report_dir: Path) -> None:
    text = (report_dir / "stdout.txt").read_text()
    assert "Leaderboard" in text and "Stasis index" in text and "Usage" in text
    oracle = next(line for line in text.splitlines() if "baseline_oracle" in line)
    assert "(baseline)" in oracle and oracle.count("100.0%") >= 4
    stasis = next(line for line in text.splitlines() if "baseline_stasis (baseline)" in line)
    assert "87.5%" in stasis and "71.2%" in stasis  # q1 and total worked out by hand


def test_json_summary_for_scripts(bpb: Callable[..., Done], report_dir: Path) -> None:
    done = bpb("report", str(report_dir / "runs"), "--json", "--bootstrap", "50")
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    board = {row["run"]: row for row in summary["leaderboard"]}
    assert board["baseline_oracle"]["total"] == 1.0
    assert board["baseline_stasis"]["total"] == pytest.approx(0.7125)
    assert summary["suites"] == {"total": {"q1": 0.3, "q2": 0.3, "q3": 0.4}}
    diagnostics = summary["diagnostics"]
    assert sorted(diagnostics) == [
        "q1_confusion", "q2_confusion", "q3_distance", "q3_distance_by_horizon",
        "q3_tolerance", "stasis",
    ]  # fmt: skip
    stasis = {row["run"]: row for row in diagnostics["stasis"]}
    assert stasis["baseline_stasis"]["motion_stasis"] == 1.0


def test_bad_input_is_one_line_and_exit_2(bpb: Callable[..., Done], tmp_path: Path) -> None:
    done = bpb("report", str(tmp_path / "missing"))
    assert done.returncode == 2
    assert done.stderr.strip().count("\n") == 0 and "no such run folder" in done.stderr


def test_exports_keep_rows_and_dtypes(report_dir: Path) -> None:
    out = report_dir / "out"
    units = pd.read_parquet(out / "units.parquet")
    assert len(units) == 3 * 4 * 17
    assert {k: str(v) for k, v in units.dtypes.items()} == UNIT_DTYPES
    calls = pd.read_parquet(out / "calls.parquet")
    assert {k: str(v) for k, v in calls.dtypes.items()} == CALL_DTYPES
    assert len(pd.read_csv(out / "units.csv")) == len(units)
    assert (out / "tables" / "leaderboard.csv").is_file()


def test_charts_are_real_non_blank_pngs(report_dir: Path) -> None:
    charts = sorted((report_dir / "out" / "charts").glob("*.png"))
    assert [p.stem for p in charts] == [
        "accuracy_by_horizon", "leaderboards", "q1_ball_collisions__metrics_beside_accuracy",
        "q3_tolerance_curve", "stasis_index",
    ]  # fmt: skip
    for path in charts:
        with Image.open(path) as img:
            assert img.width > 600 and len(img.convert("L").getcolors(1 << 16) or []) > 20


def test_html_is_self_contained(report_dir: Path) -> None:
    page = (report_dir / "out" / "report.html").read_text()
    assert not re.search(r"""(src|href)=['"]?(https?:|//|file:)""", page)
    assert "@import" not in page and "url(" not in page
    assert page.count("data:image/png;base64,") == 5 + len(
        list((report_dir / "out" / "gallery").glob("*.png"))
    )
    assert "Failure gallery" in page and "litellm_model" in page
    for title in ("Stasis index", "Q1 confusion", "Q2 confusion", "Q3 distance error (m)"):
        assert title in page  # every diagnostic of the tasks that ran has a section


@pytest.mark.slow
def test_html_renders_charts_and_gallery_in_headless_chromium(
    report_dir: Path, tmp_path: Path
) -> None:
    browser = chromium()
    page = (report_dir / "out" / "report.html").as_uri()
    common = [browser, *CHROMIUM_FLAGS, f"--user-data-dir={tmp_path / 'profile'}"]
    dom = subprocess.run(
        [*common, "--dump-dom", page], capture_output=True, text=True, timeout=120
    ).stdout
    body = re.search(r"<body[^>]*>", dom)
    assert body is not None
    images = int(re.search(r'data-images="(\d+)"', body.group(0)).group(1))  # type: ignore[union-attr]
    assert 'data-images-ok="yes"' in body.group(0) and images >= 6  # 5 charts + gallery
    assert dom.count('class="case"') >= 1 and dom.count('class="chart"') == 5
    shot = tmp_path / "shot.png"
    subprocess.run(
        [*common, f"--screenshot={shot}", "--window-size=1400,3000", page],
        capture_output=True, timeout=120, check=True,
    )  # fmt: skip
    with Image.open(shot) as img:
        assert img.size == (1400, 3000)
        grey = img.convert("L")
        assert len(grey.getcolors(1 << 16) or []) > 50  # not a blank page
        lo, hi = grey.crop((0, 600, 1400, 3000)).getextrema()  # charts region has contrast
        assert hi - lo > 150
    if os.environ.get("BPB_KEEP_SCREENSHOT"):
        shutil.copy(shot, os.environ["BPB_KEEP_SCREENSHOT"])


@pytest.mark.parametrize("value", ["nan", "1.5", "-0.1", "abc"])
def test_a_bad_completeness_threshold_is_exit_2_naming_the_option(
    bpb: Callable[..., Done], report_dir: Path, value: str
) -> None:
    done = bpb("report", str(report_dir / "runs"), "--min-complete", value)
    assert done.returncode == 2 and "--min-complete" in done.stderr


def test_include_incomplete_puts_the_run_back_marked(
    bpb: Callable[..., Done], report_dir: Path
) -> None:
    args = ("report", str(report_dir / "runs"), "--bootstrap", "20", "--json")
    board = {r["run"]: r for r in json.loads(bpb(*args).stdout)["leaderboard"]}
    assert board["litellm_model"]["total_answered"] is None
    board = {
        r["run"]: r for r in json.loads(bpb(*args, "--include-incomplete").stdout)["leaderboard"]
    }
    model = board["litellm_model"]
    assert model["q1_answered"] == 1.0 and model["short"] == "q1, q2, q3"


def test_a_gallery_with_nothing_wrong_says_so_instead_of_no_answers(
    bpb: Callable[..., Done], tmp_path: Path
) -> None:
    from support.reports_fixture import write_runs

    runs = write_runs(tmp_path)
    done = bpb("report", str(runs / "baseline_oracle"), "--out", str(tmp_path / "rep"))
    assert done.returncode == 0, done.stderr
    page = re.sub(r"\s+", " ", (tmp_path / "rep" / "report.html").read_text())
    assert "every one of the 4 fully answered scenes scored 100%: nothing to show" in page
    assert "no fully answered scenes" not in page


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        ({"options": []}, "options:"),
        ({"options": {"horizons": [float("nan")]}}, "options.horizons[0]:"),
        ({"options": {"limit": -1}}, "options.limit:"),
        ({"scene_ids": "h1_0000"}, "scene_ids:"),
        ({"scene_ids": ["h9_0000"]}, "scene_ids: h9_0000 is not a scene of"),
        ({"tasks": "q1"}, "tasks:"),
    ],
)
def test_a_hand_edited_run_json_is_refused_naming_the_field_not_read_as_no_scenes(
    bpb: Callable[..., Done], tmp_path: Path, edit: dict[str, object], field: str
) -> None:
    from support.reports_fixture import write_runs

    run = write_runs(tmp_path) / "baseline_stasis"
    manifest = json.loads((run / "run.json").read_text())
    (run / "run.json").write_text(json.dumps({**manifest, **edit}))
    done = bpb("report", str(run), "--out", str(tmp_path / "rep"))
    assert done.returncode == 2, done.stdout + done.stderr
    assert done.stderr.strip().count("\n") == 0
    assert f"{run / 'run.json'}: {field}" in done.stderr


def test_a_horizon_1_run_and_a_full_run_are_ranked_apart_and_named(
    bpb: Callable[..., Done], tmp_path: Path, dataset: Path
) -> None:
    # They were ranked together as both "complete 100%" (straight on horizon 1 only above the
    # same baseline on every horizon), with one warning naming neither runs nor horizons.
    runs = tmp_path / "runs"
    runs_of = (("baseline:stasis", ["--epochs", "2"]), ("baseline:straight", ["--horizons", "1"]))
    for adapter, extra in runs_of:
        ran = bpb("run", "--data", str(dataset), "--adapter", adapter, "--out", str(runs), *extra)
        assert ran.returncode == 0, ran.stderr
    shown = bpb("report", str(runs), "--out", str(tmp_path / "rep"))
    assert shown.returncode == 0, shown.stderr
    said = " ".join(shown.stderr.split())
    assert "the runs answered one dataset in 2 different sets of scenes;" in said
    assert "horizons 1, 3 s, 6 scenes: baseline_stasis" in said
    assert "horizons 1 s, 3 scenes: baseline_straight" in said
    summary = json.loads(bpb("report", str(runs), "--json").stdout)
    parts = {p["scenes"]: p for p in summary["datasets"]}
    assert set(parts) == {"horizons 1, 3 s, 6 scenes", "horizons 1 s, 3 scenes"}
    for scenes, run in (
        ("horizons 1, 3 s, 6 scenes", "stasis"),
        ("horizons 1 s, 3 scenes", "straight"),
    ):
        assert [r["run"] for r in parts[scenes]["leaderboard"]] == [f"baseline_{run}"]  # alone
        assert parts[scenes]["different_scenes"] is None
    page = " ".join((tmp_path / "rep" / "report.html").read_text().split())
    assert "horizons 1 s, 3 scenes" in page and "horizons 1, 3 s, 6 scenes" in page


def _stasis_runs(bpb: Callable[..., Done], dataset: Path, folder: Path, **runs: list[str]) -> None:
    """One ``baseline:stasis`` run of ``dataset`` per keyword, in ``folder/<keyword>``, with the
    keyword's extra ``bpb run`` options."""
    for name, more in runs.items():
        out = str(folder / name)
        ran = bpb(
            "run", "--data", str(dataset), "--adapter", "baseline:stasis", "--out", out, *more
        )
        assert ran.returncode == 0, ran.stderr


def test_runs_asked_other_scenes_or_more_epochs_are_told_apart(
    bpb: Callable[..., Done], tmp_path: Path, dataset: Path
) -> None:
    # Two runs asked as many scenes but not the same ones (--scenes, --sample) were ranked
    # together, while a run asked the same scenes twice (--epochs 2) was warned about as
    # asked "different numbers of scenes (12, 24 ...)".
    runs = tmp_path / "runs"
    _stasis_runs(bpb, dataset, runs, a=["--scenes", "h1_0000"], b=["--scenes", "h1_0001"])
    summary = json.loads(bpb("report", str(runs / "a"), str(runs / "b"), "--json").stdout)
    parts = summary["datasets"]  # one section per scene set, never one ranking
    assert [[r["run"] for r in p["leaderboard"]] for p in parts] == [
        ["a/baseline_stasis"],
        ["b/baseline_stasis"],
    ]
    assert [p["scenes"] for p in parts] == ["horizons 1 s, 1 scene"] * 2
    again = tmp_path / "again"
    _stasis_runs(bpb, dataset, again, once=[], twice=["--epochs", "2"])
    both = bpb("report", str(again / "once"), str(again / "twice"), "--json")
    assert json.loads(both.stdout)["different_scenes"] is None


def test_a_two_epoch_run_counts_its_scene_tasks_once_and_states_its_epochs(
    bpb: Callable[..., Done], tmp_path: Path, small_dataset: Path
) -> None:
    # With --epochs 2 every count keyed by scene-task came out doubled: the stable subset's
    # "stable scene-tasks" and the leaderboards' expected (documented as scene-task pairs),
    # accuracy's scenes; counts of answers (completeness cells, diagnostics) did not say that
    # they span two epochs.
    runs = tmp_path / "runs"
    _stasis_runs(bpb, small_dataset, runs, once=[], twice=["--epochs", "2"])
    folders = [str(runs / "once"), str(runs / "twice")]
    done = bpb("report", *folders, "--json", "--bootstrap", "20")
    once, twice = "once/baseline_stasis", "twice/baseline_stasis"
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    board = {row["run"]: row for row in summary["leaderboard"]}
    stable = {row["run"]: row for row in summary["stable"]}
    assert (board[once]["expected"], board[once]["epochs"]) == (18, 1)  # 6 scenes x 3 tasks
    assert (board[twice]["expected"], board[twice]["epochs"]) == (18, 2)
    assert 0 < stable[twice]["expected"] == stable[once]["expected"] < 18
    assert stable[twice]["epochs"] == 2
    cells = [c for c in summary["completeness"] if c["run"] == twice and c["task"] == "q1"]
    assert [(c["answered"], c["expected"], c["epochs"]) for c in cells] == [(6, 6, 2)] * 2
    scenes = {(c["run"], c["horizon"]) for c in summary["by_horizon"] if c["scenes_strict"] == 3}
    assert len(scenes) == 4  # both runs, both horizons: 3 scenes each, not 6 for the second
    stasis = {row["run"]: row for row in summary["diagnostics"]["stasis"]}
    assert (stasis[once]["epochs"], stasis[twice]["epochs"]) == (1, 2)
    assert stasis[twice]["contacts"] == 2 * stasis[once]["contacts"]  # answers, labelled

    shown = bpb("report", *folders, "--out", str(tmp_path / "rep"), "--bootstrap", "20")
    assert shown.returncode == 0, shown.stderr
    count = stable[once]["expected"]
    table = shown.stdout.split("stable scene-tasks")[1].split("└")[0]
    line = {row.split()[1]: row.split("│")[-2].strip() for row in table.splitlines()[2:]}
    assert line == {once: str(count), twice: f"{count} (x2 epochs)"}
    page = (tmp_path / "rep" / "report.html").read_text()
    assert "6 of 6 answers (3 scene-tasks x 2 epochs)" in page
    assert "3 of 3 answered" in page and "<th>scene-tasks</th>" in page
    assert "<th>epochs (answers per scene-task)</th>" in page


def test_a_run_folder_copied_under_another_name_is_counted_once_and_said_so(
    bpb: Callable[..., Done], tmp_path: Path, dataset: Path
) -> None:
    # A run folder copied under another name was ranked as a second run with the very same
    # scores, as if a second model agreed with the first.
    runs = tmp_path / "runs"
    ran = bpb("run", "--data", str(dataset), "--adapter", "baseline:stasis", "--out", str(runs))
    assert ran.returncode == 0, ran.stderr
    shutil.copytree(runs / "baseline_stasis", runs / "stasis_copy")
    ran = bpb("run", "--data", str(dataset), "--adapter", "baseline:oracle", "--out", str(runs))
    assert ran.returncode == 0, ran.stderr
    done = bpb("report", str(runs), "--json")
    assert done.returncode == 0, done.stderr
    assert [row["run"] for row in json.loads(done.stdout)["leaderboard"]] == [
        "baseline_oracle",
        "baseline_stasis",
    ]
    started = json.loads((runs / "baseline_stasis" / "run.json").read_text())["started"]
    assert done.stderr.strip() == (
        f"warning: {runs / 'stasis_copy'}: a copy of the run in {runs / 'baseline_stasis'} "
        f"(the same run.json, started {started}); counted once"
    )


def test_a_run_given_twice_is_counted_once_and_said_so(
    bpb: Callable[..., Done], report_dir: Path, tmp_path: Path
) -> None:
    # Given under other paths (or inside a folder also given), a run's calls, tokens, cost and
    # units were summed two or three times and its bootstrap intervals narrowed.
    runs = report_dir / "runs"
    once = bpb("report", str(runs), "--json", "--bootstrap", "50")
    model = runs / "litellm_model"
    again = bpb("report", str(runs), str(model), f"{model}/", "--json", "--bootstrap", "50")
    assert once.returncode == again.returncode == 0, again.stderr
    assert json.loads(again.stdout) == json.loads(once.stdout)
    line = again.stderr.strip()
    assert "\n" not in line and f"{model}: the same run folder given 3 times" in line, line
    assert "counted once" in line and once.stderr.strip() == ""
    done = bpb("report", str(model), str(model), "--out", str(tmp_path / "o"))
    assert done.returncode == 0, done.stderr
    assert len(pd.read_csv(tmp_path / "o" / "units.csv")) == 4 * 17  # one run's units


def test_gallery_headings_use_task_titles_and_say_all_right_plainly() -> None:
    """Before: "POCKETED wrong:" (the name upper-cased) and "Q2 wrong: all right"."""
    from bpb_core.report.sections import Case, render_page

    wrong = {"pocketed": [], "q2": ["TOP: said F, truth T"], "gone": []}
    case = Case("run", "h1_0000", 1.0, {"pocketed": 1.0, "q2": 0.0}, wrong)
    titles = {"q2": "Q2 wall contacts", "pocketed": "Balls pocketed"}
    page = render_page(title="t", parts=[], cases=[case], titles=titles)
    page = re.sub(r"\s+", " ", page)
    assert "<span>Balls pocketed:</span> all right" in page
    assert "<span>Q2 wall contacts wrong:</span> <ul><li>TOP: said F, truth T" in page
    assert "<span>gone:</span> all right" in page  # no title: the name as the plugin spelled it
    assert "POCKETED" not in page and "wrong: all right" not in page


def test_the_reports_gallery_names_tasks_by_their_titles(report_dir: Path) -> None:
    page = re.sub(r"\s+", " ", (report_dir / "out" / "report.html").read_text())
    assert "<span>Q1 ball collisions wrong:</span>" in page
    assert not re.search(r"<span>Q\d wrong:", page)


def test_gallery_ties_follow_scene_ids_with_numbers_read_as_numbers(
    bpb: Callable[..., Done], tmp_path: Path
) -> None:
    """Equal scores keep the scenes in id order, numbers compared as numbers: h3_9999 before
    h3_10000, h3 before h10 (sorted as text, h10_0000 came first and h3_10000 before
    h3_9999)."""
    from support.reports_fixture import stasis_answer, write_dataset, write_run

    scenes = [(10.0, 0), (3.0, 10000), (3.0, 9999)]
    ids = ["h3_9999", "h3_10000", "h10_0000"]
    same = {"q1": set(), "q2": set(), "moves": {0: (1.9, 0.9)}}  # stasis misses only ball 0
    data = write_dataset(tmp_path / "data", scenes, dict.fromkeys(ids, same))
    answers = {(s, t): {"answer": stasis_answer(s, t)} for s in ids for t in ("q1", "q2", "q3")}
    run = write_run(tmp_path / "runs" / "stasis", "baseline:stasis", data, answers, scenes=scenes)
    done = bpb("report", str(run), "--out", str(tmp_path / "out"), "--bootstrap", "10")
    assert done.returncode == 0, done.stderr
    files = sorted(p.name for p in (tmp_path / "out" / "gallery").iterdir())
    assert files == [f"{i:02d}_stasis_{sid}.png" for i, sid in enumerate(ids)]
    page = (tmp_path / "out" / "report.html").read_text()
    shown = re.findall(r"<h3>stasis &middot;\s*(\S+)</h3>", page)
    assert shown == ids
    units = pd.read_csv(tmp_path / "out" / "units.csv")
    assert units["scene_id"].drop_duplicates().tolist() == ids  # the tables' order too
