"""PNG files of the scene images (8-bit palette), deflated by zlib-ng.

Pillow's PNG encoder deflates with the zlib it was built with; zlib-ng (``zlib-ng`` on PyPI)
at level 2 makes smaller files in less time. The file is an ordinary PNG (8-bit palette, no
filter, not interlaced: signature, IHDR, PLTE, one IDAT, IEND) that any decoder reads to the
pixels of the image it was made from.
"""

from __future__ import annotations

import struct

from PIL import Image
from zlib_ng import zlib_ng

SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _chunk(kind: bytes, data: bytes) -> bytes:
    """A PNG chunk: length, type, data and the CRC-32 of type and data."""
    crc = zlib_ng.crc32(data, zlib_ng.crc32(kind))
    return b"".join((struct.pack(">I", len(data)), kind, data, struct.pack(">I", crc)))


def encode_palette_png(img: Image.Image, level: int) -> bytes:
    """PNG bytes of a palette image, deflated by zlib-ng at ``level`` (0-9; the same bytes for
    equal images and zlib-ng version).

    Raises:
        ValueError: ``img`` is not an 8-bit palette ("P") image, or has a transparent colour
            (scene images have none).
    """
    if img.mode != "P" or "transparency" in img.info:
        raise ValueError(
            f"encode_palette_png: expected an opaque palette (P) image, got mode {img.mode}"
            + (" with transparency" if "transparency" in img.info else "")
        )
    width, height = img.size
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 3, 0, 0, 0)
    plte = bytes(img.getpalette() or [0, 0, 0])
    # PNG deflates each row behind its filter byte (0, none). Pillow's raw encoder writes rows
    # width + 1 bytes apart with a zero after each (its stride argument); a zero in front puts
    # each zero before the next row instead, and the last one is left out.
    rows = memoryview(img.tobytes("raw", ("P", width + 1)))
    deflate = zlib_ng.compressobj(level, zlib_ng.DEFLATED, 15, 9)
    data = deflate.compress(b"\0") + deflate.compress(rows[:-1]) + deflate.flush()
    chunks = (_chunk(b"IHDR", ihdr), _chunk(b"PLTE", plte), _chunk(b"IDAT", data))
    return b"".join((SIGNATURE, *chunks, _chunk(b"IEND", b"")))
