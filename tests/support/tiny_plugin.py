"""Install the ``bpb-tiny`` test plugin (``tests/third_party/bpb_tiny``) for real, without pip.

A site folder gets a ``bpb_tiny-0.1.0.dist-info`` whose ``bpb`` entry point is
``tiny = "bpb_tiny.hooks"``; with the site folder and ``tests/third_party`` on ``PYTHONPATH``,
``importlib.metadata`` finds the plugin exactly as it finds a pip-installed one. Commands then
run through the real ``bpb`` console script, and any other subprocess (the fake OpenAI server)
gets the same environment.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

from support.plugin_dist import write_dist_info

SOURCE = Path(__file__).resolve().parents[1] / "third_party"
BPB = Path(sys.executable).with_name("bpb")
DIST, VERSION = "bpb-tiny", "0.1.0"


@dataclass(frozen=True)
class TinyInstall:
    """The site folder holding the plugin's metadata and the environment that sees it."""

    site: Path
    env: dict[str, str]

    def bpb(self, *args: str | Path, timeout: float = 120) -> subprocess.CompletedProcess[str]:
        """Run ``bpb ARGS`` with the plugin installed; output is captured as text."""
        command = [str(BPB), *map(str, args)]
        return subprocess.run(
            command, capture_output=True, text=True, env=self.env, timeout=timeout, check=False
        )

    def ok(self, *args: str | Path) -> str:
        """Run ``bpb ARGS``, insist on exit code 0 and return its standard output."""
        done = self.bpb(*args)
        assert done.returncode == 0, f"bpb {' '.join(map(str, args))}: {done.stderr}"
        return done.stdout


def install_tiny(site: Path) -> TinyInstall:
    """Write the dist-info into ``site`` and return the environment that finds it."""
    write_dist_info(site, DIST, VERSION, {"tiny": "bpb_tiny.hooks"})
    # an existing PYTHONPATH (a git worktree's src) stays after the plugin's folders
    path = os.pathsep.join(filter(None, [str(site), str(SOURCE), os.environ.get("PYTHONPATH")]))
    return TinyInstall(site, {**os.environ, "PYTHONPATH": path, "OPENAI_API_KEY": "dummy"})
