"""The scene PNGs bpb writes with zlib-ng: valid files that decode to the drawn pixels.

Checked two ways: with Pillow's decoder, and by hand with the standard library alone (chunk
CRCs by ``zlib.crc32``, the data inflated by stock zlib, the filter bytes read), so the files
are not only what our own encoder and Pillow agree on.
"""

from __future__ import annotations

import io
import struct
import zlib

import pytest
from hypothesis import given, settings, strategies as strat
from PIL import Image

from bpb_tasks.billiards.render.canvas import CanvasSpec
from bpb_tasks.billiards.render.images import render_init
from bpb_tasks.billiards.render.png import encode_palette_png
from bpb_tasks.billiards.scene.config import DatasetConfig
from bpb_tasks.billiards.scene.model import Ball, Scene

SPEC = CanvasSpec.from_config(DatasetConfig())


def chunks(data: bytes) -> list[tuple[bytes, bytes]]:
    """(type, data) of every chunk, each chunk's CRC checked with the standard library."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    found, pos = [], 8
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind, body = data[pos + 4 : pos + 8], data[pos + 8 : pos + 8 + length]
        (crc,) = struct.unpack(">I", data[pos + 8 + length : pos + 12 + length])
        assert crc == zlib.crc32(kind + body), kind
        found.append((kind, body))
        pos += 12 + length
    assert pos == len(data)
    return found


def by_hand(data: bytes) -> tuple[tuple[int, int], bytes, bytes]:
    """Size, palette and pixel rows of an 8-bit palette PNG without filters, read with the
    standard library (stock zlib inflates what zlib-ng deflated)."""
    found = chunks(data)
    kinds = [kind for kind, _ in found]
    assert kinds[0] == b"IHDR" and kinds[-1] == b"IEND" and b"PLTE" in kinds
    width, height, depth, colour, *rest = struct.unpack(">IIBBBBB", found[0][1])
    assert (depth, colour, *rest) == (8, 3, 0, 0, 0)
    raw = zlib.decompress(b"".join(body for kind, body in found if kind == b"IDAT"))
    assert len(raw) == height * (width + 1)
    rows = [raw[y * (width + 1) : (y + 1) * (width + 1)] for y in range(height)]
    assert {row[0] for row in rows} <= {0}  # filter type None on every row
    return (width, height), dict(found)[b"PLTE"], b"".join(row[1:] for row in rows)


def a_scene() -> Scene:
    balls = [
        Ball(id=0, pos=(0.4, 0.5), vel=(0.8, 0.3)),
        Ball(id=1, pos=(1.2, 0.45), vel=(0.0, 0.0)),
        Ball(id=5, pos=(1.7, 0.8), vel=(0.0, 0.0)),
    ]
    return Scene(scene_id="h2_0000", horizon=2.0, balls=balls)


def test_a_scene_image_decodes_to_the_drawn_pixels_and_palette() -> None:
    img = render_init(a_scene(), SPEC)
    data = encode_palette_png(img, 2)
    size, palette, pixels = by_hand(data)
    assert size == img.size and pixels == img.tobytes()
    assert list(palette) == img.getpalette()
    with Image.open(io.BytesIO(data)) as back:
        back.load()
        assert back.mode == "P" and back.tobytes() == img.tobytes()
        assert back.getpalette() == img.getpalette()


def test_the_default_level_writes_smaller_files_than_pillow_level_1() -> None:
    """What the default trades: zlib-ng's level 2 against the Pillow level 1 bpb used before."""
    img = render_init(a_scene(), SPEC)
    pillow = io.BytesIO()
    img.save(pillow, format="PNG", compress_level=1)
    assert len(encode_palette_png(img, DatasetConfig().image.compress_level)) < pillow.tell()


@settings(max_examples=60, deadline=None)
@given(
    width=strat.integers(1, 40),
    height=strat.integers(1, 12),
    colours=strat.integers(1, 256),
    level=strat.integers(0, 9),
    data=strat.data(),
)
def test_any_palette_image_round_trips(
    width: int, height: int, colours: int, level: int, data: strat.DataObject
) -> None:
    pixels = data.draw(strat.binary(min_size=width * height, max_size=width * height))
    img = Image.frombytes("P", (width, height), bytes(p % colours for p in pixels))
    palette = data.draw(strat.binary(min_size=3 * colours, max_size=3 * colours))
    img.putpalette(palette)
    encoded = encode_palette_png(img, level)
    size, plte, decoded = by_hand(encoded)
    assert size == (width, height) and decoded == img.tobytes()
    assert plte == bytes(img.getpalette() or [])
    with Image.open(io.BytesIO(encoded)) as back:
        back.load()
        assert back.mode == "P" and back.size == img.size
        assert back.tobytes() == img.tobytes()
        assert back.convert("RGB").tobytes() == img.convert("RGB").tobytes()
    assert encode_palette_png(img, level) == encoded  # the same image, the same bytes


@pytest.mark.parametrize(
    ("img", "said"),
    [
        (Image.new("RGB", (4, 4)), "got mode RGB"),
        (Image.new("L", (4, 4)), "got mode L"),
    ],
)
def test_other_modes_are_refused(img: Image.Image, said: str) -> None:
    with pytest.raises(ValueError, match=said):
        encode_palette_png(img, 2)


def test_a_transparent_palette_colour_is_refused() -> None:
    img = Image.new("P", (4, 4))
    img.info["transparency"] = 0
    with pytest.raises(ValueError, match="with transparency"):
        encode_palette_png(img, 2)
