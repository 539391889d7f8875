"""A person answers ten scenes of ``bpb human`` in headless Chromium, with a reload, a restart of
the app, a skip, a step back and an undo on the way; the run then holds exactly the answers the
page showed when each was saved, and is scored on them. An untouched page is refused."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import pytest

from bpb_core.dataset import generate_dataset
from bpb_core.registry import Registry
from bpb_core.results import load_results
from bpb_core.run_folder import iter_answers
from bpb_core.runner.options import RunOptions
from bpb_core.web.human import HumanSession, human_app
from bpb_tasks.billiards.scene.model import Scene
from bpb_tasks.billiards.truth.final import FinalState
from support.web_server import chromium, free_port, serving

sync_api = pytest.importorskip("playwright.sync_api")
pytestmark = pytest.mark.slow
WALLS = ("TOP", "BOTTOM", "LEFT", "RIGHT")


@pytest.fixture(scope="module")
def ten_scenes(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("person") / "ds"
    return generate_dataset(out, per_horizon=5, horizons=[1.0, 3.0], seed=4, workers=1)


@pytest.fixture
def page() -> Any:
    with sync_api.sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium(), args=["--no-sandbox"])
        context = browser.new_context(viewport={"width": 1500, "height": 1000})
        yield context.new_page()
        browser.close()


def scene_id(page: Any) -> str:
    return str(page.locator('#answer-form input[name="scene"]').get_attribute("value"))


def answer(page: Any, step: int) -> None:
    """Fill the page as a person: a ball and a wall ticked or "none", ball 0 moved by the arrow
    keys, ball 1 typed, ball 2 onto a pocket by typing, every other ball confirmed resting."""
    balls = page.locator('input[name^="q1.ball"]')
    if step % 3 == 0:
        page.locator('input[name="q1.none"]').check()
    else:
        balls.nth(step % balls.count()).check()
    if step % 2:
        page.locator('input[name="q2.none"]').check()
    else:
        page.locator(f'input[name="q2.{WALLS[step % 4]}"]').check()
    for button in page.locator("button.rests").all():
        button.click()
    marker = page.locator('.marker[data-ball="0"]')
    marker.focus()
    for _ in range(step + 1):
        page.keyboard.press("ArrowRight")
    page.keyboard.press("Shift+ArrowUp")
    typed = page.locator("#q3-pos1")
    typed.fill(f"{0.3 + 0.1 * step:.4f},0.4000")
    typed.dispatch_event("change")
    if page.locator("#q3-pos2").count():
        page.locator("#q3-pos2").fill("pocket")
        page.locator("#q3-pos2").dispatch_event("change")


def shown(page: Any) -> dict[str, Any]:
    """What the page says now: ticked boxes and every ball's place."""
    ticked = [
        box.get_attribute("name")
        for box in page.locator('input[type="checkbox"]').all()
        if box.is_checked()
    ]
    places = {
        int(str(i.get_attribute("data-ball"))): i.input_value()
        for i in page.locator('input[name^="q3.pos"]').all()
    }
    return {"ticked": sorted(str(t) for t in ticked), "places": places}


def save(page: Any) -> None:
    with page.expect_navigation():
        page.locator("#submit").click()


def test_a_person_answers_ten_scenes_through_reload_restart_skip_back_and_undo(
    page: Any, ten_scenes: Path, tmp_path: Path, registry: Registry
) -> None:
    run = tmp_path / "human_pat"
    port = free_port()

    def session() -> HumanSession:
        return HumanSession(ten_scenes, run, "pat", registry, RunOptions(), seed=5)

    given: dict[str, dict[str, Any]] = {}
    first = session()
    order = [ref.scene_id for ref in first.order]
    assert len(order) == 10
    with serving(human_app(first), port) as url:
        page.goto(url + "/")
        save(page)  # untouched: refused, nothing stored
        assert "q1.none: missing" in page.locator("#error-message").inner_text()
        assert list(iter_answers(run)) == []
        page.goto(url + "/")
        assert scene_id(page) == order[0]
        with page.expect_navigation():
            page.locator("#skip").click()  # asked last
        for step in range(1, 5):
            assert scene_id(page) == order[step]
            answer(page, step)
            if step == 2:  # a reload keeps ticks, places and the markers on them
                before = shown(page)
                page.reload()
                assert shown(page) == before
                marker = page.locator('.marker[data-ball="0"]')
                assert "unplaced" not in str(marker.get_attribute("class"))
            given[scene_id(page)] = shown(page)
            save(page)
        answer(page, 5)  # half-way through scene 5, the app stops and starts again
        given[order[5]] = shown(page)
    with serving(human_app(session()), port) as url:
        save(page)  # the old page's post: refused (another token), its draft kept
        assert "app restarted: reload the page" in page.locator("#error-message").inner_text()
        page.goto(url + "/")
        assert scene_id(page) == order[5] and shown(page) == given[order[5]]
        save(page)
        # back: scene 5 again, as saved; a changed tick replaces its answer
        page.locator("#back").click()
        page.wait_for_load_state()
        assert scene_id(page) == order[5] and page.locator("#answered-before").count() == 1
        assert shown(page) == given[order[5]]
        page.locator('input[name="q2.none"]').check()
        given[order[5]] = shown(page)
        save(page)
        for step in range(6, 10):
            assert scene_id(page) == order[step]
            answer(page, step)
            given[order[step]] = shown(page)
            save(page)
        # undo: the last save (scene 9) is removed and asked again, its draft restored
        with page.expect_navigation():
            page.locator("#undo").click()
        assert scene_id(page) == order[9] and shown(page) == given[order[9]]
        assert len({sid for sid, _ in ((r.scene_id, r.task) for _, r in iter_answers(run))}) == 8
        save(page)
        assert scene_id(page) == order[0]  # the skipped scene comes last
        answer(page, 0)
        given[order[0]] = shown(page)
        save(page)
        assert page.locator("#done").count() == 1
    check_stored_and_scored(run, ten_scenes, given, registry)


def check_stored_and_scored(
    run: Path, data: Path, given: dict[str, dict[str, Any]], registry: Registry
) -> None:
    stored = {(r.scene_id, r.task): r.answer for _, r in iter_answers(run)}
    assert {sid for sid, _ in stored} == set(given)
    units = load_results([run], registry=registry).units
    for sid, page_said in given.items():
        folder = next(p.parent for p in data.glob("h*/scene_*/init.json") if sid in p.read_text())
        scene = Scene.model_validate_json((folder / "init.json").read_text())
        truth = FinalState.model_validate_json((folder / "final.json").read_text())
        ticked = set(page_said["ticked"])
        q1 = {a["id"]: a["answer"] for a in stored[(sid, "q1")]["answers"]}
        assert q1 == {i: "T" if f"q1.ball{i}" in ticked else "F" for i in q1}
        q2 = {a["wall"]: a["answer"] for a in stored[(sid, "q2")]["answers"]}
        assert q2 == {w: "T" if f"q2.{w}" in ticked else "F" for w in WALLS}
        q3 = {p["id"]: p["pos"] for p in stored[(sid, "q3")]["predictions"]}
        for ball, text in page_said["places"].items():
            expect = None if text == "pocket" else [float(v) for v in text.split(",")]
            assert q3[ball] == expect
        # scored on exactly these answers: each unit right where it equals the truth
        mine = units[units["scene_id"] == sid]
        true_q1 = {int(lab.id): lab.answer for lab in truth.q1}
        true_q2 = {str(lab.wall): lab.answer for lab in truth.q2}
        true_q3 = {int(p.id): p.pos for p in truth.predictions}
        radius = scene.physics.ball_radius
        for row in mine.to_dict(orient="records"):
            if row["task"] == "q1":
                assert bool(row["correct"]) == (q1[int(row["unit"])] == true_q1[int(row["unit"])])
            elif row["task"] == "q2":
                assert bool(row["correct"]) == (q2[str(row["unit"])] == true_q2[str(row["unit"])])
            else:
                guess, real = q3[int(row["unit"])], true_q3[int(row["unit"])]
                right = (guess is None and real is None) or (
                    guess is not None and real is not None and math.dist(guess, real) <= radius
                )
                assert bool(row["correct"]) == right
