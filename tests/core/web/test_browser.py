"""A person answers three scenes of ``bpb human`` in headless Chromium (ticks and drags), the run
is scored by ``bpb report``, and ``bpb view``'s filters and pair page are used, all through
Playwright driving the system's Chromium."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path
from typing import Any

import pytest

from bpb_core.registry import Registry
from bpb_core.report.build import build_report
from bpb_core.run_folder import iter_answers
from bpb_core.runner import evaluate
from bpb_core.runner.options import RunOptions
from bpb_core.web.human import HumanSession, human_app
from bpb_core.web.viewer import Viewer, viewer_app
from bpb_tasks.billiards.render.canvas import CanvasSpec
from bpb_tasks.billiards.scene.config import load_config
from support.web_server import chromium, serving

sync_api = pytest.importorskip("playwright.sync_api")
pytestmark = pytest.mark.slow


@pytest.fixture
def runs_dir(small_dataset: Path, tmp_path: Path, registry: Registry) -> Path:
    """The oracle's run, made before Playwright's event loop starts in this thread."""
    evaluate(small_dataset, ["baseline:oracle"], tmp_path / "runs", registry=registry)
    return tmp_path / "runs"


@pytest.fixture
def browser() -> Any:
    executable = chromium()
    with sync_api.sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=executable, args=["--no-sandbox"])
        yield browser
        browser.close()


def _shot(page: Any, tmp_path: Path, name: str) -> None:
    path = tmp_path / f"{name}.png"
    page.screenshot(path=str(path), full_page=True)
    keep = os.environ.get("BPB_KEEP_SCREENSHOTS")
    if keep:
        shutil.copy(path, Path(keep) / path.name)


def _drag(page: Any, ball: int, table_xy: tuple[float, float]) -> None:
    """Drag ball ``ball``'s marker to table point ``table_xy``."""
    spec = CanvasSpec.from_config(load_config(None))
    image = page.locator("#scene-image").bounding_box()
    scale = image["width"] / spec.size[0]
    px, py = spec.to_px(*table_xy)
    marker = page.locator(f'.marker[data-ball="{ball}"]').bounding_box()
    page.mouse.move(marker["x"] + marker["width"] / 2, marker["y"] + marker["height"] / 2)
    page.mouse.down()
    page.mouse.move(image["x"] + px * scale, image["y"] + py * scale, steps=8)
    page.mouse.up()


def _answers(run: Path) -> dict[tuple[str, str], Any]:
    return {(r.scene_id, r.task): r for _, r in iter_answers(run)}


def test_people_answer_in_the_browser_and_the_viewer_shows_every_pair(
    runs_dir: Path, browser: Any, small_dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    run = runs_dir / "human_tester"
    session = HumanSession(small_dataset, run, "tester", registry, RunOptions(), seed=3)
    page = browser.new_page(viewport={"width": 1500, "height": 1000})
    with serving(human_app(session)) as url:
        asked = []
        for step in range(3):
            page.goto(url + "/")
            sid = page.locator('#answer-form input[name="scene"]').get_attribute("value")
            asked.append(sid)
            assert page.locator("#scene-image").evaluate("i => i.naturalWidth") > 0
            assert "Task Q1" in page.locator("pre.prompt").first.inner_text()
            page.locator('input[name="q1.ball2"]').check()
            page.locator('input[name="q2.TOP"]').check()
            for rests in page.locator("button.rests").all():  # every ball placed or resting
                rests.click()
            _drag(page, 0, (0.5 + 0.3 * step, 0.5))
            _drag(page, 1, (2.0, 1.0))  # onto the top-right pocket
            if step == 0:
                _shot(page, tmp_path, "human")
            with page.expect_navigation():  # the post, its redirect and the next page
                page.locator("#submit").click()
        assert asked == [ref.scene_id for ref in session.order[:3]]  # the seeded order
        # a forged post is refused with a message and stores nothing
        before = len(_answers(run))
        forged_form = {"scene": session.order[3].scene_id, "shown": "1", "q1.ball99": "T"}
        forged_form["token"] = session.token
        reply = page.request.post(url + "/answer", form=forged_form)
        assert reply.status == 400 and "q1.ball99: not a field" in reply.text()
        assert len(_answers(run)) == before == 9
    answers = _answers(run)
    for step, sid in enumerate(asked):
        q1, q2, q3 = (answers[(sid, t)].answer for t in ("q1", "q2", "q3"))
        assert {a["id"]: a["answer"] for a in q1["answers"]}[2] == "T"
        assert {a["wall"]: a["answer"] for a in q2["answers"]}["TOP"] == "T"
        placed = {p["id"]: p["pos"] for p in q3["predictions"]}
        assert placed[1] is None  # dropped on a pocket
        assert abs(placed[0][0] - (0.5 + 0.3 * step)) < 0.01 and abs(placed[0][1] - 0.5) < 0.01
        assert 0 < answers[(sid, "q1")].latency < 600
    # scored beside a model: completeness is the share of the 6 scenes answered
    board = build_report([runs_dir], registry=registry, n_boot=20).tables["summary"]
    human = board[board["run"] == "human_tester"].iloc[0]
    assert human["completeness"] == pytest.approx(0.5) and human["adapter"] == "human:tester"
    # an attempt whose text is markup is shown as text, never run
    with (run / "attempts.jsonl").open("a") as log:
        markup = "<script>window.pwned = 1</script><b>bold</b>"
        forged = {"scene_id": asked[0], "task": "q1", "attempt": 2, "outcome": "parse_error"}
        forged |= {"text": markup, "error": "<i>x</i>"}
        log.write(json.dumps(forged) + "\n")
    viewer = Viewer.load([runs_dir], registry)
    with serving(viewer_app(viewer)) as url:
        page.goto(url + "/")
        assert page.locator("tr.pair").count() == 36  # 2 runs x 6 scenes x 3 tasks
        page.select_option("#filter-model", "human:tester")
        page.select_option("#filter-verdict", "unanswered")
        with page.expect_navigation():
            page.locator("#apply").click()
        assert page.locator("tr.pair").count() == 9
        page.goto(url + "/?model=baseline:oracle&task=q1&horizon=3")
        assert page.locator('tr.pair[data-verdict="correct"]').count() == 3
        page.goto(url + "/?stable=stable&model=baseline:oracle")
        stable = page.locator("tr.pair").count()
        assert 0 < stable <= 18
        page.goto(url + "/?model=human:tester&task=q1")
        with page.expect_navigation():
            page.locator(f'tr.pair a:text-is("{asked[0]}")').click()
        page.wait_for_load_state("networkidle")
        for image in ("#input-image", "#overlay-image"):
            assert page.locator(image).evaluate("i => i.naturalWidth") > 0
        assert "Task Q1" in page.locator("pre.prompt").first.inner_text()
        assert page.locator("#units tbody tr").count() == 6
        replies = page.locator("pre.reply").all_inner_texts()
        assert any("<script>window.pwned = 1</script>" in text for text in replies)
        assert page.evaluate("() => window.pwned") is None
        _shot(page, tmp_path, "viewer_pair")
        bad = page.goto(url + "/?model=<b>nope</b>")
        assert bad is not None and bad.status == 400
        assert "<b>nope</b>" in page.locator("#error-message").inner_text()
