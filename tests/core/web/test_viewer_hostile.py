"""``bpb view`` on hostile or damaged run folders and datasets answers a page or a 4xx naming
the problem, never a bare 500."""

from __future__ import annotations

import json
from pathlib import Path

from starlette.testclient import TestClient

from bpb_core.registry import Registry
from bpb_core.web.viewer import Viewer, viewer_app

MODEL = 2  # litellm_model, after baseline_oracle and baseline_stasis


def _client(runs: Path, registry: Registry) -> TestClient:
    app = viewer_app(Viewer.load([runs], registry))
    return TestClient(app, base_url="http://127.0.0.1", raise_server_exceptions=False)


def test_a_hand_edited_attempts_log_is_shown_not_a_500(runs: Path, registry: Registry) -> None:
    lines = [
        {"scene_id": "h1_0001", "task": "q2", "attempt": 1, "outcome": "parse_error"}
        | {"text": "lone \udc80 surrogate", "error": "e \ud800", "escalation": "abc"},
        {"scene_id": "h1_0001", "task": "q2", "attempt": 2, "outcome": "parse_error"}
        | {"text": "x", "escalation": float("inf"), "reasoning": "r \udfff"},
    ]
    with (runs / "litellm_model" / "attempts.jsonl").open("w") as log:
        log.writelines(json.dumps(line) + "\n" for line in lines)  # ASCII: "\udc80" escapes
    (runs.parent / "data" / "h1" / "scene_0001" / "init.png").write_bytes(b"any image")
    reply = _client(runs, registry).get(f"/pair/{MODEL}/h1_0001/q2")
    assert reply.status_code == 200
    assert "lone \ufffd surrogate" in reply.text and "e \ufffd" in reply.text
    assert "<summary>escalation 0</summary>" in reply.text


def test_a_dataset_without_its_images_still_shows_its_pairs(runs: Path, registry: Registry) -> None:
    # the hand-made dataset has no init.png, as after ``bpb generate --no-images``
    client = _client(runs, registry)
    page = client.get(f"/pair/{MODEL}/h1_0000/q1")
    assert page.status_code == 200 and 'id="prompt-note"' in page.text
    assert "cannot read the input image" in page.text
    image = client.get(f"/image/{MODEL}/h1_0000")
    assert image.status_code == 404 and "init.png" in image.text
    assert client.get(f"/overlay/{MODEL}/h1_0000/q1").status_code == 200


def test_a_page_number_that_is_not_ascii_digits_is_a_400(runs: Path, registry: Registry) -> None:
    client = _client(runs, registry)
    for page in ("\u00b2", "\u0663", "1\u00b9"):  # str.isdigit() is true, int() fails or not
        reply = client.get("/", params={"page": page})
        assert reply.status_code == 400 and "page: expected a page number" in reply.text
    assert client.get("/", params={"page": "1"}).status_code == 200
