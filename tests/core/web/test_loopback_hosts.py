"""The apps built by ``human_app`` and ``viewer_app`` answer only requests addressed to 127.0.0.1
or localhost however they are served: a library caller running them with their own uvicorn gets
the same DNS-rebinding guard as ``bpb human`` and ``bpb view``."""

from __future__ import annotations

import http.client
from pathlib import Path
from typing import Any

import pytest

from bpb_core.registry import Registry
from bpb_core.runner.options import RunOptions
from bpb_core.web.human import HumanSession, human_app
from bpb_core.web.viewer import Viewer, viewer_app
from support.web_server import serving


def _status(url: str, host: str) -> tuple[int, str]:
    port = int(url.rsplit(":", 1)[1])
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=20)
    try:
        conn.request("GET", "/", headers={"Host": host})
        response = conn.getresponse()
        return response.status, response.read().decode()
    finally:
        conn.close()


def _apps(name: str, runs: Path, small_dataset: Path, tmp_path: Path, registry: Registry) -> Any:
    if name == "viewer":
        return viewer_app(Viewer.load([runs], registry))
    options = RunOptions(horizons=(1.0,))
    return human_app(HumanSession(small_dataset, tmp_path / "human", "ann", registry, options))


@pytest.mark.parametrize("name", ["viewer", "human"])
def test_an_app_served_by_plain_uvicorn_refuses_other_hosts(
    name: str, runs: Path, small_dataset: Path, tmp_path: Path, registry: Registry
) -> None:
    with serving(_apps(name, runs, small_dataset, tmp_path, registry)) as url:
        port = url.rsplit(":", 1)[1]
        refused, body = _status(url, f"evil.example:{port}")
        assert refused == 400 and "token" not in body and "pair" not in body
        assert _status(url, "evil.example")[0] == 400
        for host in (f"127.0.0.1:{port}", f"localhost:{port}"):
            assert _status(url, host)[0] == 200
