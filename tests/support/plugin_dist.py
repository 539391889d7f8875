"""Install throw-away plugin distributions for real, without pip.

A distribution here is what pip leaves behind: modules (or a package folder) and a
``*.dist-info`` folder with ``METADATA`` and ``entry_points.txt`` on a ``sys.path`` entry.
``importlib.metadata`` finds it exactly as it finds a pip-installed plugin, so discovery is
tested end to end without network.
"""

from __future__ import annotations

import textwrap
from collections.abc import Callable
from pathlib import Path

InstallFn = Callable[[str, str, dict[str, str], dict[str, str]], None]


def install_fake_dist(
    site: Path, dist: str, version: str, modules: dict[str, str], entry_points: dict[str, str]
) -> None:
    """Write modules and a dist-info folder for ``dist`` into ``site``."""
    site.mkdir(parents=True, exist_ok=True)
    for name, source in modules.items():
        (site / f"{name}.py").write_text(textwrap.dedent(source))
    write_dist_info(site, dist, version, entry_points)


def write_dist_info(site: Path, dist: str, version: str, entry_points: dict[str, str]) -> Path:
    """A ``*.dist-info`` folder declaring ``entry_points`` in the ``bpb`` group."""
    site.mkdir(parents=True, exist_ok=True)
    info = site / f"{dist.replace('-', '_')}-{version}.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: {version}\n")
    lines = "\n".join(f"{name} = {target}" for name, target in entry_points.items())
    (info / "entry_points.txt").write_text(f"[bpb]\n{lines}\n")
    return info
