"""``bpb human`` without a browser: seeded order, resume, and every bad post refused with a
message while nothing is stored."""

from __future__ import annotations

import asyncio
import functools
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
from starlette.testclient import TestClient

from bpb_core.errors import BadInput
from bpb_core.registry import Registry
from bpb_core.run_folder import iter_answers, read_manifest
from bpb_core.runner.options import RunOptions
from bpb_core.web.human import HumanSession, human_app
from support.inprocess import bpb
from support.web_server import free_port

BPB = str(Path(sys.executable).with_name("bpb"))
LOCAL = "http://127.0.0.1"  # the apps answer only requests addressed to loopback names


def _session(data: Path, run: Path, registry: Registry, seed: int = 0) -> HumanSession:
    return HumanSession(data, run, "ann", registry, RunOptions(horizons=(1.0,)), seed)


def _valid_form(client: TestClient) -> dict[str, str]:
    page = client.get("/").text
    form = dict(re.findall(r'name="(scene|shown|token)" value="([^"]+)"', page))
    rests = r'class="rests" data-ball="(\d+)"\s+data-start="([^"]+)"'  # each ball rests
    form |= {f"q3.pos{ball}": start for ball, start in re.findall(rests, page)}
    return form | {"q1.ball1": "T", "q2.none": "T", "ms.q1": "1500"}


def test_order_is_seeded_and_a_new_session_resumes(
    small_dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    first = _session(small_dataset, tmp_path / "a", registry, seed=1)
    again = _session(small_dataset, tmp_path / "b", registry, seed=1)
    other = [_session(small_dataset, tmp_path / f"c{s}", registry, seed=s) for s in range(2, 6)]
    assert [r.scene_id for r in first.order] == [r.scene_id for r in again.order]
    assert any([r.scene_id for r in o.order] != [r.scene_id for r in first.order] for o in other)
    client = TestClient(human_app(first), base_url=LOCAL)
    form = _valid_form(client) | {"shown": f"{time.time() - 2:.3f}", "ms.q2": "9000"}
    reply = client.post("/answer", data=form, follow_redirects=False)
    assert reply.status_code == 303
    resumed = _session(small_dataset, tmp_path / "a", registry, seed=1)
    resumed_at = resumed.next_scene()
    assert resumed_at is not None and resumed_at.scene_id == first.order[1].scene_id
    stored = [r for _, r in iter_answers(tmp_path / "a")]
    assert {r.task for r in stored} == {"q1", "q2", "q3"} and all(r.status == "ok" for r in stored)
    assert {r.adapter for r in stored} == {"human:ann"}
    latency = {r.task: r.latency for r in stored}  # the page's timing, capped by the server's
    assert latency["q1"] == pytest.approx(1.5, abs=0.01)
    assert latency["q2"] == pytest.approx(2.0, abs=0.5)
    manifest = read_manifest(tmp_path / "a")
    assert manifest is not None and manifest["adapter"] == "human:ann"
    assert len(manifest["sessions"]) == 2


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"q1.ball9": "T"}, "q1.ball9: not a field of this form"),
        ({"q1.ball1": "yes"}, "q1.ball1: a ticked box posts T"),
        ({"q3.pos2": "3.5,0.2"}, "q3.pos2: (3.5, 0.2) is off the table"),
        ({"q3.pos2": "a,b"}, "q3.pos2: expected &#39;x,y&#39; in metres"),
        ({"q3.pos2": None}, "q3.pos2: missing"),
        ({"ms.q1": "-4"}, "ms.q1: expected whole milliseconds"),
        ({"ms.q1": "\u00b2"}, "ms.q1: expected whole milliseconds"),  # isdigit(), not int()
        ({"scene": "h9_0000"}, "scene: not a scene of this session"),
        ({"q1.ball1": None}, "q1.none: missing"),  # an untouched Q1 is no answer
        ({"q2.TOP": "T"}, "q2.none: ticked together with TOP"),
        ({"q3.pos1": ""}, "q3.pos1: missing (place ball 1 or confirm it rests"),
        ({"shown": "soon"}, "shown: expected the time"),
        ({"q2.TOP": "T" * 500}, "longer than 200 characters"),
        ({"<script>x": "T"}, "&lt;script&gt;x: not a field"),
        ({"token": "0" * 32}, "token: not this session"),
    ],
)
def test_a_bad_post_is_refused_with_its_field_and_stores_nothing(
    small_dataset: Path,
    tmp_path: Path,
    registry: Registry,
    change: dict[str, str | None],
    message: str,
) -> None:
    client = TestClient(human_app(_session(small_dataset, tmp_path, registry)), base_url=LOCAL)
    form = _valid_form(client)
    for key, value in change.items():
        if value is None:
            form.pop(key)
        else:
            form[key] = value
    reply = client.post("/answer", data=form, follow_redirects=False)
    assert reply.status_code == 400 and message in reply.text
    assert "<script>x" not in reply.text
    assert list(iter_answers(tmp_path)) == []


def test_a_name_that_is_not_a_plain_word_is_bad_input(
    small_dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    with pytest.raises(BadInput, match="--name"):
        HumanSession(small_dataset, tmp_path, "<bob>", registry)


def test_the_closing_page_comes_when_every_scene_is_answered(
    small_dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    session = _session(small_dataset, tmp_path, registry)
    client = TestClient(human_app(session), base_url=LOCAL)
    for _ in session.order:
        assert client.post("/answer", data=_valid_form(client)).status_code == 200
    assert 'id="done"' in client.get("/").text and session.next_scene() is None


def test_the_apps_listen_on_loopback_only_on_the_port_asked_or_a_free_one() -> None:
    from bpb_core import web as serving

    with serving.listen(0) as sock:  # --port 0: the system picks, and the URL names it
        host, port = sock.getsockname()
        assert host == "127.0.0.1" and port > 0
        assert serving.url(sock) == f"http://127.0.0.1:{port}/"
        with pytest.raises(BadInput) as taken:
            serving.listen(port)
    assert str(taken.value).startswith(f"--port {port}: cannot listen on 127.0.0.1:{port} (")
    assert str(taken.value).endswith("choose another with --port, or --port 0 for a free one")


def test_a_taken_port_is_one_line_exit_2_and_makes_no_run_folder(
    capfd: pytest.CaptureFixture[str], small_dataset: Path, tmp_path: Path
) -> None:
    from bpb_core import web as serving

    run = tmp_path / "run"
    with serving.listen(0) as held:  # another program on the port
        port = str(held.getsockname()[1])
        done = bpb(capfd, "human", "--data", str(small_dataset), "--out", str(run), "--port", port)
        viewed = bpb(capfd, "view", str(tmp_path), "--port", port)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1
    assert f"--port {port}: cannot listen" in done.stderr and "Errno" not in done.stderr
    assert not run.exists()
    assert viewed.returncode == 2 and f"--port {port}: cannot listen" in viewed.stderr


def test_bad_command_lines_are_one_line_errors(
    capfd: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    run_bpb = functools.partial(bpb, capfd)
    viewed = run_bpb("view", str(tmp_path / "nope"))
    assert viewed.returncode == 2 and "no such run folder" in viewed.stderr
    human = run_bpb("human", "--data", str(tmp_path / "nodata"), "--out", str(tmp_path / "run"))
    assert human.returncode == 2 and "--data" in human.stderr
    assert len(human.stderr.strip().splitlines()) == 1


def test_a_huge_post_is_refused_before_it_is_read_whole(
    small_dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    """Any web page can post to the app: 100 fields of 900 kB (under Starlette's default limits)
    must not be read into memory before being refused."""
    app = human_app(_session(small_dataset, tmp_path, registry))
    field = b"a" * 900_000
    chunks = iter([b"f%d=" % i + field + b"&" for i in range(100)])
    pulled = 0
    sent: list[dict[str, object]] = []

    async def receive() -> dict[str, object]:
        nonlocal pulled
        chunk = next(chunks, b"")
        pulled += len(chunk)
        return {"type": "http.request", "body": chunk, "more_body": bool(chunk)}

    async def send(message: dict[str, object]) -> None:
        sent.append(message)

    scope = {
        "type": "http", "method": "POST", "path": "/answer", "raw_path": b"/answer",
        "query_string": b"", "root_path": "", "scheme": "http", "http_version": "1.1",
        "headers": [
            (b"host", b"127.0.0.1:8765"),
            (b"content-type", b"application/x-www-form-urlencoded"),
        ],
        "server": ("127.0.0.1", 8765), "client": ("127.0.0.1", 50000),
    }  # fmt: skip
    asyncio.run(app(scope, receive, send))
    start = next(m for m in sent if m["type"] == "http.response.start")
    body = b"".join(m.get("body", b"") for m in sent if m["type"] == "http.response.body")
    assert start["status"] == 400 and b"form: Field exceeded maximum size" in body
    assert pulled <= 1_000_000  # the first chunk, not 90 MB
    assert list(iter_answers(tmp_path)) == []


def test_a_second_bpb_human_on_one_run_folder_is_refused_while_the_first_serves(
    small_dataset: Path, tmp_path: Path
) -> None:
    """Two sessions on one folder both started: two people answered the same scenes and the
    later answer file replaced the earlier (and each rewrote ``run.json``)."""
    run = tmp_path / "run"
    args = ["human", "--data", str(small_dataset), "--out", str(run), "--port", str(free_port())]
    first = subprocess.Popen([BPB, *args], stderr=subprocess.PIPE, text=True)
    try:
        assert first.stderr is not None and "open http" in first.stderr.readline()
        manifest = (run / "run.json").read_bytes()
        again = [BPB, *args[:-1], str(free_port())]  # a process: it must not serve for ever
        second = subprocess.run(again, capture_output=True, text=True, timeout=60)
        assert first.poll() is None
    finally:
        first.terminate()
        first.wait(timeout=30)
    assert second.returncode == 2
    assert second.stderr.strip().splitlines() == [
        f"error: {run}: in use by another bpb run or bpb human (pid {first.pid}); wait for it "
        "to finish or stop it, then re-run to resume"
    ]
    assert (run / "run.json").read_bytes() == manifest


def test_a_persons_run_is_reported_as_scenes_answered_not_calls_unsent(
    small_dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    from bpb_core.results import load_results
    from bpb_core.results.tables import incomplete_lines

    session = _session(small_dataset, tmp_path / "human_ann", registry)
    client = TestClient(human_app(session), base_url=LOCAL)
    form = _valid_form(client) | {"shown": f"{time.time() - 30:.3f}", "ms.q1": "12000"}
    form |= {"ms.q2": "20000", "ms.q3": "25000"}
    assert client.post("/answer", data=form, follow_redirects=False).status_code == 303
    lines = incomplete_lines(load_results([tmp_path / "human_ann"], registry=registry))
    said = lines["human_ann"]
    assert said.startswith(f"a person's session: 1 of {len(session.order)} scenes answered")
    assert "25 s per scene (median)" in said  # the slowest task's time
    assert "never sent" not in said and "calls" not in said
