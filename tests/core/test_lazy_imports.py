"""Importing the core and building the registry must not pull heavy libraries in."""

from __future__ import annotations

import subprocess
import sys

HEAVY = ("litellm", "pandas", "matplotlib", "pymunk", "openai", "pyarrow", "inspect_ai", "datasets")


def _modules_after(code: str) -> set[str]:
    probe = f"{code}\nimport sys\nprint(' '.join(sorted(sys.modules)))"
    result = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True
    )
    return set(result.stdout.split())


def test_import_core_and_registry_stays_light() -> None:
    loaded = _modules_after("import bpb_core\nfrom bpb_core import make_registry\nmake_registry()")
    assert not loaded & set(HEAVY)


def test_cli_help_imports_neither_pydantic_nor_heavy_libraries() -> None:
    code = (
        "import sys\nfrom bpb_core.cli.main import cli\n"
        "try:\n    cli.main(['--help'], standalone_mode=False)\nexcept SystemExit:\n    pass"
    )
    loaded = _modules_after(code)
    assert not loaded & {*HEAVY, "pydantic", "numpy", "rich"}


def test_public_names_resolve_lazily() -> None:
    import importlib

    import bpb_core

    exports = bpb_core._EXPORTS
    for name in bpb_core.__all__:
        if name == "__version__":
            continue
        real = getattr(importlib.import_module(exports[name]), name)
        assert getattr(bpb_core, name) is real, name
