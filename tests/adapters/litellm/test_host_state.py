"""The litellm adapter leaves the calling program's environment and logging as it found them,
and still loads litellm's bundled price map (no fetch)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

PROBE = """
import json, logging, os
if os.environ.get("HOST_LEVEL"):
    logging.getLogger("LiteLLM").setLevel(int(os.environ["HOST_LEVEL"]))
from bpb_adapters.litellm_adapter.adapter import _import_litellm
_import_litellm()
from litellm.litellm_core_utils.get_model_cost_map import _cost_map_source_info
print(json.dumps({
    "env": os.environ.get("LITELLM_LOCAL_MODEL_COST_MAP"),
    "level": logging.getLogger("LiteLLM").level,
    "prices": _cost_map_source_info.source,
}))
"""


@pytest.mark.parametrize(
    ("host_env", "host_level", "level"),
    [(None, None, 40), ("False", "10", 10)],
)
def test_importing_litellm_leaves_the_callers_environment_and_log_level(
    host_env: str | None, host_level: str | None, level: int
) -> None:
    """LITELLM_LOCAL_MODEL_COST_MAP=True stayed in the caller's environment (its own later
    litellm calls and child processes inherited it), and the LiteLLM logger was set to ERROR
    over a level the caller had chosen."""
    env = {k: v for k, v in os.environ.items() if k not in ("LITELLM_LOCAL_MODEL_COST_MAP",)}
    env["PYTHONPATH"] = os.pathsep.join(sys.path)
    if host_env is not None:
        env["LITELLM_LOCAL_MODEL_COST_MAP"] = host_env
    if host_level is not None:
        env["HOST_LEVEL"] = host_level
    done = subprocess.run(
        [sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    (line,) = [text for text in done.stdout.splitlines() if text.startswith("{")]
    seen = json.loads(line)  # (litellm logs at the DEBUG level the caller asked for)
    assert seen == {"env": host_env, "level": level, "prices": "local"}
