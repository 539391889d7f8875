"""``bpb view``'s pages say what a researcher looks for: each run's dataset, runs over different
datasets apart, Q3 per ball with predicted and true centres and the distance, and an item with
no answer shown as unanswered (never ``nan`` or "wrong")."""

from __future__ import annotations

import html
import re
from pathlib import Path

from starlette.testclient import TestClient

from bpb_core.registry import Registry
from bpb_core.runner import evaluate
from bpb_core.web.viewer import Viewer, viewer_app


def _cells(page: str, row: str) -> list[str]:
    return [html.unescape(c) for c in re.findall(r"<t[dh][^>]*>(.*?)</t[dh]>", row)]


def test_pairs_name_their_dataset_and_q3_shows_centres_and_distance(
    small_dataset: Path, runs: Path, tmp_path: Path, registry: Registry
) -> None:
    mine = tmp_path / "mine"
    evaluate(small_dataset, ["baseline:stasis"], mine, registry=registry)
    stasis = next(mine.iterdir())
    gone = next(stasis.glob("h*/scene_*/q3.json"))
    gone.unlink()  # one pair never answered
    viewer = Viewer.load([mine, runs], registry)
    client = TestClient(viewer_app(viewer), base_url="http://127.0.0.1")
    index = client.get("/").text
    sections = re.findall(r'<tr class="dataset"><th colspan="9">dataset (.*?)</th>', index)
    assert len(sections) == 2 and len(set(sections)) == 2  # one section per dataset
    assert "2 datasets" in index
    ours = next(s for s in sections if s.startswith("ds ("))
    only_ours = client.get("/", params={"dataset": html.unescape(ours)}).text
    assert 'class="pair"' in only_ours and "litellm_model" not in only_ours

    run_id = [run.path for run in viewer.results.runs].index(stasis)
    answered = next(p for p in stasis.glob("h*/scene_*/q3.json"))
    scene_id = next(k.scene_id for k in viewer.results.runs[run_id].scene_keys
                    if k.dir(stasis) == answered.parent)  # fmt: skip
    page = client.get(f"/pair/{run_id}/{scene_id}/q3").text
    assert f"dataset {html.unescape(ours)}" in html.unescape(page)
    table = page[
        page.index('<table id="units">') : page.index("</table>", page.index('id="units"'))
    ]
    rows = re.findall(r"<tr>(.*?)</tr>", table, re.S)
    head = _cells(page, rows[0])
    assert head[:5] == ["item", "truth", "answer", "verdict", "distance"]
    assert {"truth (x, y)", "pred (x, y)", "start (x, y)"} <= set(head)
    for row in rows[1:]:
        cell = dict(zip(head, _cells(page, row), strict=True))
        if cell["truth"] == "pos":  # stasis predicts the start: pred equals start
            assert re.fullmatch(r"\(\d\.\d{4}, \d\.\d{4}\)", cell["truth (x, y)"])
            assert cell["pred (x, y)"] == cell["start (x, y)"]
            assert float(cell["distance"]) >= 0
        assert cell["verdict"] in ("right", "wrong")
        assert ">nan<" not in row

    lost = next(k.scene_id for k in viewer.results.runs[run_id].scene_keys
                if k.dir(stasis) == gone.parent)  # fmt: skip
    page = client.get(f"/pair/{run_id}/{lost}/q3").text
    assert 'id="verdict" class="missing">unanswered' in page
    table = page[page.index('<table id="units">') :]
    assert "unanswered" in table and ">nan<" not in table.split("</table>")[0]
