"""DNS rebinding in headless Chromium: a site whose name is made to resolve to 127.0.0.1 reaches
the app's port, but the app answers only requests addressed to 127.0.0.1 or localhost."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from bpb_core.registry import Registry
from bpb_core.web.viewer import Viewer, viewer_app
from support.web_server import chromium, serving

sync_api = pytest.importorskip("playwright.sync_api")
pytestmark = pytest.mark.slow


@pytest.fixture
def browser() -> Any:
    executable = chromium()
    rules = "MAP rebound.example 127.0.0.1, MAP localhost 127.0.0.1"  # what rebinding does
    with sync_api.sync_playwright() as playwright:
        args = ["--no-sandbox", f"--host-resolver-rules={rules}"]
        browser = playwright.chromium.launch(executable_path=executable, args=args)
        yield browser
        browser.close()


def test_a_rebound_name_gets_a_400_and_loopback_names_the_pages(
    runs: Path, registry: Registry, browser: Any
) -> None:
    app = viewer_app(Viewer.load([runs], registry))
    page = browser.new_page()
    with serving(app) as url:
        port = url.rsplit(":", 1)[1]
        rebound = page.goto(f"http://rebound.example:{port}/")
        assert rebound is not None and rebound.status == 400
        assert page.locator("tr.pair").count() == 0
        for name in ("127.0.0.1", "localhost"):
            shown = page.goto(f"http://{name}:{port}/")
            assert shown is not None and shown.status == 200
            assert page.locator("tr.pair").count() > 0
