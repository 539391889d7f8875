"""Fixtures of the batch tests: the fake server (its batch endpoints on 127.0.0.1) with a
batch config, and small requests with an image in each provider's body format.

Each request's prompt shows an answer example unique to it (``{"answers": [i]}``), which the
server answers with (an unknown prompt is answered with its example), so that a test can tell
every reply apart; every such prompt has the server's key ``unknown/unknown``, whose fault plan
is then consumed one entry per request in the order the batch processes them.
"""

from __future__ import annotations

import base64
import io
import json
import urllib.request
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest
from PIL import Image

from support.fake_openai import FakeServer, fake_server


@dataclass
class BatchServer:
    """The running fake server and its batch controls."""

    server: FakeServer

    @property
    def url(self) -> str:
        return self.server.url

    def advance(self, seconds: float) -> None:
        """Move the server's clock on."""
        self.server._post("/batch/clock", {"advance": seconds})

    def stats(self) -> dict[str, Any]:
        with urllib.request.urlopen(self.url + "/batch/stats", timeout=10) as response:
            data: dict[str, Any] = json.loads(response.read())
        return data

    def paid(self) -> dict[str, int]:
        """Billed answers per custom_id."""
        return dict(self.stats()["paid"])


@pytest.fixture
def batch_server(tmp_path: Path) -> Callable[..., AbstractContextManager[BatchServer]]:
    """``with batch_server(batch={...}, faults={...}) as server:`` runs the fake server with
    that batch config and fault plan."""

    @contextmanager
    def start(**config: Any) -> Iterator[BatchServer]:
        with fake_server(None, config, tmp_path) as server:
            yield BatchServer(server)

    return start


@dataclass(frozen=True)
class Requests:
    """Request ``i`` in each provider's body format, with the scene image; ``answer(i)`` is
    what the server replies to it."""

    png: bytes

    @staticmethod
    def prompt(i: int) -> str:
        return f'Which balls does the cue ball hit? Answer as JSON like {{"answers": [{i}]}}.'

    @staticmethod
    def answer(i: int) -> dict[str, Any]:
        return {"answers": [i]}

    @property
    def b64(self) -> str:
        return base64.b64encode(self.png).decode()

    def chat(self, i: int, model: str = "gpt-4.1-mini") -> dict[str, Any]:
        url = "data:image/png;base64," + self.b64
        content = [
            {"type": "text", "text": self.prompt(i)},
            {"type": "image_url", "image_url": {"url": url}},
        ]
        return {
            "model": model,
            "messages": [{"role": "user", "content": content}],
            "max_tokens": 200,
        }

    def responses(self, i: int, model: str = "gpt-5.4-pro") -> dict[str, Any]:
        url = "data:image/png;base64," + self.b64
        content = [
            {"type": "input_text", "text": self.prompt(i)},
            {"type": "input_image", "image_url": url},
        ]
        return {"model": model, "input": [{"role": "user", "content": content}],
                "reasoning": {"effort": "high"}}  # fmt: skip

    def anthropic(self, i: int, model: str = "claude-opus-4-7") -> dict[str, Any]:
        image = {"type": "base64", "media_type": "image/png", "data": self.b64}
        content = [{"type": "image", "source": image}, {"type": "text", "text": self.prompt(i)}]
        return {
            "model": model,
            "max_tokens": 400,
            "messages": [{"role": "user", "content": content}],
        }

    def gemini(self, i: int) -> dict[str, Any]:
        """A generateContent request in REST form (camelCase), as an input file holds it."""
        parts = [
            {"text": self.prompt(i)},
            {"inlineData": {"mimeType": "image/png", "data": self.b64}},
        ]
        return {
            "contents": [{"role": "user", "parts": parts}],
            "generationConfig": {"temperature": 0},
        }


@pytest.fixture(scope="session")
def requests() -> Requests:
    """Requests with a small PNG, the scene image of every request."""
    out = io.BytesIO()
    Image.new("RGB", (16, 12), (20, 120, 40)).save(out, "PNG")
    return Requests(out.getvalue())
