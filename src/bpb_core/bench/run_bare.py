"""The reference client of ``bpb bench run``: a bare ``litellm.acompletion`` loop.

It sends ``n`` requests with ``concurrency`` in flight and nothing else: no parsing, no files.
For a fair comparison the requests carry what ``bpb run`` sends: the first scene's image and its
q1, q2 and q3 prompts, in turn. Run as
``python -m bpb_core.bench.run_bare API_BASE N CONCURRENCY DATA``.
"""

from __future__ import annotations

import asyncio
import base64
import importlib
import os
import sys
from pathlib import Path
from typing import Any


def prompts(data: Path) -> list[tuple[bytes, str]]:
    """The image and the q1, q2, q3 prompt texts of the dataset's first scene."""
    from bpb_core.interfaces import PromptOptions
    from bpb_core.registry import make_registry
    from bpb_core.runner.scenes import select_scenes

    ref = select_scenes(data, None, 1)[0]
    scene, image, registry = ref.load(), ref.image(), make_registry()
    out = []
    for name in ("q1", "q2", "q3"):
        task = registry.task(name)
        out.append((image, task.prompt_text(scene, PromptOptions(cot=task.default_cot))))
    return out


def _messages(image: bytes, text: str) -> list[dict[str, Any]]:
    uri = "data:image/png;base64," + base64.b64encode(image).decode("ascii")
    content = [{"type": "image_url", "image_url": {"url": uri}}, {"type": "text", "text": text}]
    return [{"role": "user", "content": content}]


async def bare_loop(api_base: str, n: int, concurrency: int, data: Path) -> int:
    """Send ``n`` requests, ``concurrency`` at a time; return how many succeeded."""
    os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
    litellm: Any = importlib.import_module("litellm")
    bodies = [_messages(image, text) for image, text in prompts(data)]
    slots = asyncio.Semaphore(concurrency)
    ok = 0

    async def one(i: int) -> None:
        nonlocal ok
        async with slots:
            await litellm.acompletion(
                model="openai/fake-model",
                messages=bodies[i % len(bodies)],
                api_base=api_base,
                temperature=0.0,
                timeout=60,
                max_retries=0,
            )
            ok += 1

    await asyncio.gather(*(one(i) for i in range(n)))
    return ok


def main() -> None:
    """Command-line entry: API_BASE N CONCURRENCY DATA."""
    api_base, n, concurrency, data = sys.argv[1:5]
    done = asyncio.run(bare_loop(api_base, int(n), int(concurrency), Path(data)))
    sys.exit(0 if done == int(n) else 1)


if __name__ == "__main__":
    main()
