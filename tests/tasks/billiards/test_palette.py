"""The default canvas's palette ships with the package; it must be the palette computed.

Every drawing process needs the palette, and computing it (a sample image and its median cut)
cost about 0.1 s of CPU per process; the shipped file saves that only if using it changes no
image byte, so it must hold exactly what computing gives, and be ignored for anything else.
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import pytest

from bpb_tasks.billiards import render_palette
from bpb_tasks.billiards.config import DatasetConfig
from bpb_tasks.billiards.render_canvas import CanvasSpec
from bpb_tasks.billiards.render_palette import SHIPPED, computed_colours, palette_for, palette_key

SPEC = CanvasSpec.from_config(DatasetConfig())
REFRESH = "run `python scripts/refresh_palette.py` and commit render_palette.json"


def test_the_shipped_palette_is_what_the_default_canvas_computes() -> None:
    stored = json.loads(SHIPPED.read_text())
    assert stored["key"] == palette_key(SPEC), (
        f"{SHIPPED.name} was made from another style, canvas, Pillow or font files "
        f"(every process now computes the palette): {REFRESH}"
    )
    assert bytes.fromhex(stored["colours"]) == bytes(computed_colours(SPEC)), (
        f"{SHIPPED.name} holds other colours than the default canvas computes: {REFRESH}"
    )


def test_a_fresh_process_takes_the_default_palette_without_drawing_its_sample() -> None:
    code = (
        "from bpb_tasks.billiards import render_canvas, render_style\n"
        "from bpb_tasks.billiards.config import DatasetConfig\n"
        "from bpb_tasks.billiards.render_palette import palette_for, computed_colours\n"
        "spec = render_canvas.CanvasSpec.from_config(DatasetConfig())\n"
        "palette = palette_for(spec).image.getpalette()\n"
        "drawn = render_canvas.background.cache_info().currsize\n"
        "drawn += render_style.ball_sprite.cache_info().currsize\n"
        "print(drawn, palette == computed_colours(spec))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["0", "True"]


def test_another_canvas_computes_its_own_palette() -> None:
    other = dataclasses.replace(SPEC, ppm=450.0)
    assert palette_key(other) != palette_key(SPEC)
    assert palette_for(other).image.getpalette() == computed_colours(other)
    assert palette_for(other).image.getpalette() != palette_for(SPEC).image.getpalette()


@pytest.mark.parametrize("damage", ["stale key", "short palette", "not json"])
def test_a_shipped_file_that_does_not_fit_is_ignored(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, damage: str
) -> None:
    stored = json.loads(SHIPPED.read_text())
    if damage == "stale key":
        stored["key"] = "0" * 64
    elif damage == "short palette":
        stored["colours"] = stored["colours"][:-6]
    text = "{" if damage == "not json" else json.dumps(stored)
    (tmp_path / "palette.json").write_text(text)
    monkeypatch.setattr(render_palette, "SHIPPED", tmp_path / "palette.json")
    computed = palette_for.__wrapped__(SPEC).image.getpalette()  # past the per-process cache
    assert computed == computed_colours(SPEC)
