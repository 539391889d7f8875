"""The words of a published dataset card for billiards scenes (``bpb export --format hf``)."""

from __future__ import annotations

from typing import Any

PRETTY_NAME = "BilliardPhys-Bench scenes"

DESCRIPTION = """\
Billiards scenes with physics ground truth, for testing whether multimodal models can
predict what happens on a table: seven balls at rest, the cue ball (ball 0) struck with a
given velocity, rolling friction, elastic collisions, six pockets. For each scene and horizon
`t` there are three questions: **q1** which object balls the cue ball touches in `[0, t]`,
**q2** which walls it touches, **q3** where every ball is at `t` (`null` when pocketed).

The image is the scene's input image (the table, numbered balls, the cue velocity as an arrow
with its speed). The prompts state the constants and laws, the horizon and the answer format;
`prompt_image` goes with the image, `prompt_image_state` with the image and the initial state as
JSON, `prompt_state` alone (text only). `target` is the correct answer in the task's JSON format;
`stable` is false when some label flips under a small perturbation of the initial state
(`stability.delta`, 0.1 mm by default; margins in `stability`). Scores follow the paper: q1
per-ball accuracy, q2 exact wall-set match, q3 a ball is right within one radius of the truth;
total = 0.3 q1 + 0.3 q2 + 0.4 q3."""

CITATION = """\
@misc{wang2026billiardphysbench,
  title  = {BilliardPhys-Bench: Benchmarking Physical Reasoning and Visual Dynamics of
            Multimodal LLMs},
  author = {Wang, Ben and Li, Xiaogang and Gao, Ruochen and Xiao, Peiyao and Xu, Chengliang
            and Wang, Zeyu and Chen, Zichao and Zhao, Bing and Wei, Hu},
  year   = {2026}
}"""


def dataset_card() -> dict[str, Any]:
    """The card's words (see :class:`bpb_core.capabilities.DescribesDataset`)."""
    return {
        "pretty_name": PRETTY_NAME,
        "description": DESCRIPTION,
        "citation": CITATION,
        "license": "mit",
        "task_categories": ["visual-question-answering"],
        "tags": ["physics", "billiards", "physical-reasoning", "multimodal", "benchmark"],
    }
