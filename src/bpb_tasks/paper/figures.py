"""The scores the BilliardPhys-Bench paper states in its text, per model, as data.

Only figures the paper writes out are here: its bar charts give more, but values read off a
chart would be guesses. A figure without a horizon is the paper's mean over its horizons 1-5 s
(accuracy averaged over horizons; ``total`` is 0.3 Q1 + 0.3 Q2 + 0.4 Q3 of those means). The
section is where the paper states it.
"""

from __future__ import annotations

from bpb_core.registry import Figure, ReferenceInfo

SOURCE = (
    "Wang, Li et al., BilliardPhys-Bench: Benchmarking Physical Reasoning and Visual Dynamics "
    "of Multimodal LLMs (figures stated in its text)"
)
RESULTS, DISCUSSION = "Results", "Discussion"

# (model, metric, percent, horizon or None for the mean, section)
STATED: tuple[tuple[str, str, float, float | None, str], ...] = (
    ("GPT-5.4-Pro", "q1", 78.02, None, f"{RESULTS}: Task 1"),
    ("GPT-5.5", "q1", 74.43, None, f"{RESULTS}: Task 1"),
    ("GPT-5.4", "q1", 15.66, None, f"{RESULTS}: Task 1"),
    ("Claude-Opus-4.7", "q1", 20.01, None, f"{RESULTS}: Task 1"),
    ("GPT-5.5", "q2", 90.34, None, f"{RESULTS}: Task 2"),
    ("Qwen3.6-Plus", "q2", 87.39, None, f"{RESULTS}: Task 2"),
    ("Claude-Opus-4.6", "q2", 89.54, 5.0, f"{RESULTS}: Task 2"),
    ("GPT-5.4-Pro", "q3", 87.93, 1.0, f"{RESULTS}: Task 3"),
    ("GPT-5.5", "q3", 86.93, 1.0, f"{RESULTS}: Task 3"),
    ("GPT-5.5", "total", 73.58, None, f"{RESULTS}: Overall"),
    ("GPT-5.4-Pro", "total", 72.29, None, f"{RESULTS}: Overall"),
    ("GPT-5.2-Pro", "total", 62.34, None, f"{RESULTS}: Overall"),
    ("Gemini-3-Flash-Preview", "total", 58.06, None, f"{DISCUSSION}: Gemini"),
    ("Gemini-3.1-Pro-Preview", "total", 53.84, None, f"{DISCUSSION}: Gemini"),
    ("Qwen3.6-Plus", "total", 57.36, None, f"{DISCUSSION}: Qwen"),
    ("Qwen3.5-Plus", "total", 43.09, None, f"{DISCUSSION}: Qwen"),
    ("Qwen3-VL-Plus", "total", 22.23, None, f"{DISCUSSION}: Qwen"),
    ("Qwen3.6-Plus", "q1", 47.66, None, f"{DISCUSSION}: Qwen"),
    ("Qwen3.6-Plus", "q3", 57.00, 1.0, f"{DISCUSSION}: Qwen"),
    ("Qwen3.6-Plus", "q3", 44.71, 5.0, f"{DISCUSSION}: Qwen"),
    ("Claude-Opus-4.6", "q2", 82.50, None, f"{DISCUSSION}: Claude"),
    ("Claude-Opus-4.7", "q3", 77.93, 1.0, f"{DISCUSSION}: Claude"),
    ("Claude-Opus-4.7", "q3", 62.27, 5.0, f"{DISCUSSION}: Claude"),
    ("Claude-Opus-4.7", "q2", 22.55, None, f"{DISCUSSION}: Claude"),
    ("Doubao-Seed-2.0-Pro", "total", 48.46, None, f"{DISCUSSION}: Kimi and Doubao"),
    ("Doubao-Seed-1.8", "total", 37.26, None, f"{DISCUSSION}: Kimi and Doubao"),
    ("Doubao-Seed-1.8", "q1", 33.36, None, f"{DISCUSSION}: Kimi and Doubao"),
    ("Doubao-Seed-2.0-Pro", "q1", 26.37, None, f"{DISCUSSION}: Kimi and Doubao"),
    ("Doubao-Seed-1.8", "q2", 67.73, None, f"{DISCUSSION}: Kimi and Doubao"),
    ("Doubao-Seed-2.0-Pro", "q2", 78.11, None, f"{DISCUSSION}: Kimi and Doubao"),
    ("Doubao-Seed-1.8", "q3", 21.07, None, f"{DISCUSSION}: Kimi and Doubao"),
    ("Doubao-Seed-2.0-Pro", "q3", 49.03, None, f"{DISCUSSION}: Kimi and Doubao"),
    ("Kimi-K2.5", "total", 41.95, None, f"{DISCUSSION}: Kimi and Doubao"),
    ("Kimi-K2.5", "q1", 30.04, None, f"{DISCUSSION}: Kimi and Doubao"),
    ("Kimi-K2.5", "q2", 71.26, None, f"{DISCUSSION}: Kimi and Doubao"),
    ("Kimi-K2.5", "q3", 33.53, None, f"{DISCUSSION}: Kimi and Doubao"),
    ("GPT-5.4", "q3", 80.86, 1.0, f"{DISCUSSION}: Modeling vs. calculation"),
)


def paper_reference() -> ReferenceInfo:
    """The paper's stated figures as a reference record."""
    figures = tuple(
        Figure(model, metric, percent / 100, horizon, where)
        for model, metric, percent, horizon, where in STATED
    )
    return ReferenceInfo(
        "paper",
        summary="Scores the BilliardPhys-Bench paper states, per model",
        source=SOURCE,
        figures=figures,
        horizons=(1.0, 2.0, 3.0, 4.0, 5.0),
    )
