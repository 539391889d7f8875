"""The reference client of ``bpb bench run``: a bare ``litellm.acompletion`` loop.

It sends ``n`` requests with ``concurrency`` in flight and nothing else: no parsing, no files.
For a fair comparison the requests carry what ``bpb run`` sends: the messages of each default
task of the dataset's scene family about its first scene (with its image, when the family has
images), in turn. Run as ``python -m bpb_core.bench.run_bare API_BASE N CONCURRENCY DATA``.
"""

from __future__ import annotations

import asyncio
import base64
import importlib
import os
import sys
from pathlib import Path
from typing import Any

from bpb_core.interfaces import InputMode, PromptOptions
from bpb_core.model_calls import ImagePart, Message, TextPart

CALL_TIMEOUT = 60
"""Seconds either client of ``bpb bench run`` waits for one reply: the server's latency must
stay below it."""


def input_mode(data: Path) -> InputMode:
    """``image`` when the dataset's scene family has images, else ``state``."""
    from bpb_core.dataset.reader import open_folder

    return "image" if open_folder(data).family.input_image else "state"


def requests(data: Path) -> list[list[dict[str, Any]]]:
    """The chat messages of each default task about the dataset's first scene, as litellm
    takes them."""
    from bpb_core.registry import make_registry
    from bpb_core.runner.asking import asking
    from bpb_core.runner.options import RunOptions

    ask = asking(data, RunOptions(limit=1), make_registry())
    ref = ask.scenes[0]
    scene = ref.load()
    image = ref.image() if ask.family.input_image else None
    mode: InputMode = "image" if image is not None else "state"
    out = []
    for task in ask.tasks.values():
        prompt = PromptOptions(input_mode=mode, cot=task.default_cot)
        out.append([_message(m) for m in task.messages(scene, image, prompt)])
    return out


def _message(message: Message) -> dict[str, Any]:
    """One message in the OpenAI chat format (text alone as a string, as the adapter does)."""
    if all(isinstance(p, TextPart) for p in message.parts):
        text = "\n\n".join(p.text for p in message.parts if isinstance(p, TextPart))
        return {"role": message.role, "content": text}
    return {"role": message.role, "content": [_part(p) for p in message.parts]}


def _part(part: TextPart | ImagePart) -> dict[str, Any]:
    if isinstance(part, TextPart):
        return {"type": "text", "text": part.text}
    uri = f"data:{part.media_type};base64," + base64.b64encode(part.data).decode("ascii")
    return {"type": "image_url", "image_url": {"url": uri}}


async def bare_loop(api_base: str, n: int, concurrency: int, data: Path) -> int:
    """Send ``n`` requests, ``concurrency`` at a time; return how many succeeded."""
    os.environ.setdefault("LITELLM_LOCAL_MODEL_COST_MAP", "True")
    litellm: Any = importlib.import_module("litellm")
    bodies = requests(data)
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
                timeout=CALL_TIMEOUT,
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
