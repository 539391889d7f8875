"""Start the fake OpenAI-compatible server (bpb_testing.fakeserver) in a subprocess."""

from __future__ import annotations

import json
import subprocess
import sys
import urllib.request
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any


@dataclass
class FakeServer:
    """A running fake server on 127.0.0.1."""

    port: int
    process: subprocess.Popen[str]

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    @property
    def api_base(self) -> str:
        return f"{self.url}/v1"

    def _post(self, path: str, body: dict[str, Any]) -> Any:
        request = urllib.request.Request(
            self.url + path, json.dumps(body).encode(), {"Content-Type": "application/json"}
        )
        with urllib.request.urlopen(request, timeout=10) as response:
            return json.loads(response.read())

    def stats(self) -> dict[str, Any]:
        with urllib.request.urlopen(self.url + "/stats", timeout=10) as response:
            data: dict[str, Any] = json.loads(response.read())
        return data

    def counts(self) -> dict[str, int]:
        return dict(self.stats()["counts"])

    def configure(self, config: dict[str, Any]) -> None:
        self._post("/config", config)


@contextmanager
def fake_server(
    data: Path | None, config: dict[str, Any] | None = None, tmp: Path | None = None
) -> Iterator[FakeServer]:
    """Run the server for the duration of the block."""
    args = [sys.executable, "-m", "bpb_testing.fakeserver"]
    if data is not None:
        args += ["--data", str(data)]
    if config is not None:
        assert tmp is not None
        path = tmp / "fake_config.json"
        path.write_text(json.dumps(config))
        args += ["--config", str(path)]
    process = subprocess.Popen(args, stdout=subprocess.PIPE, text=True)
    try:
        assert process.stdout is not None
        line = process.stdout.readline()
        assert line.startswith("PORT "), line
        yield FakeServer(int(line.split()[1]), process)
    finally:
        process.kill()
        process.wait()
