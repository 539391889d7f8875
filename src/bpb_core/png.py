"""PNG files of palette images, deflated by zlib-ng: what a scene family writes its images with.

Pillow's PNG encoder deflates with stock zlib (1.2.13 in its wheels): at level 1 that is most of
the 2.3-4 ms one 1364 x 780 palette image costs on the benchmark machine. zlib-ng (the
maintained, SIMD-accelerated zlib; ``zlib-ng`` on PyPI) at level 2 makes a file a fifth smaller
in about a third of the time (docs/benchmarks.md, issue 12, stop 31). The file is an ordinary
PNG (8-bit palette, no filter, not interlaced) that any decoder reads to the same pixels as
Pillow's file of the same image.

The data PNG deflates is each row behind its filter byte (0, none). :class:`RowImage` is drawn
on in place in such a buffer; any other image's rows are copied once, by Pillow's core, into a
zeroed buffer mapped as an image whose rows lie one byte apart (``Image.frombuffer`` with a
stride of width + 1, at an offset of one byte), so the zeros between them are the filter bytes:
0.13 ms for a 1364 x 780 image, where ``Image.tobytes`` alone takes about 1 ms.
"""

from __future__ import annotations

import struct

from PIL import Image
from zlib_ng import zlib_ng

SIGNATURE = b"\x89PNG\r\n\x1a\n"
DEFAULT_LEVEL = 2  # zlib-ng: smaller files than Pillow's level 1 at a third of its CPU


def _chunk(kind: bytes, data: bytes | memoryview) -> bytes:
    """A PNG chunk: length, type, data and the CRC-32 of type and data."""
    crc = zlib_ng.crc32(data, zlib_ng.crc32(kind))
    return b"".join((struct.pack(">I", len(data)), kind, data, struct.pack(">I", crc)))


def _header(img: Image.Image) -> bytes:
    """Signature, IHDR (8-bit palette, not interlaced) and PLTE."""
    width, height = img.size
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 3, 0, 0, 0)
    plte = bytes(img.getpalette() or [0, 0, 0])
    return b"".join((SIGNATURE, _chunk(b"IHDR", ihdr), _chunk(b"PLTE", plte)))


def _mapped(rows: bytearray, size: tuple[int, int]) -> Image.Image:
    """A palette image whose pixels are ``rows`` as :func:`filtered_rows` lays them out
    (shared, not copied; read-only to Pillow until told otherwise)."""
    at_one = memoryview(rows)[1:]  # any buffer maps; Pillow's annotation names fewer types
    return Image.frombuffer("P", size, at_one, "raw", "P", size[0] + 1, 1)  # type: ignore[arg-type]


def filtered_rows(img: Image.Image) -> bytearray:
    """The rows of an 8-bit image, each behind a zero (its PNG filter byte), and one more zero
    at the end (not part of the PNG data)."""
    width, height = img.size
    rows = bytearray(height * (width + 1) + 1)
    # the core's copy writes into ``rows``
    _mapped(rows, img.size).im.paste(img.im, (0, 0, width, height))
    return rows


class RowImage:
    """A palette image drawn in place in the data its PNG deflates.

    Made from the :func:`filtered_rows` of a template (a background, say) and its palette, its
    :attr:`image` is an ordinary Pillow image to draw on, whose pixels are those rows: encoding
    it copies nothing, and making it copies the template once (``bytearray``), where copying
    the template image and then its rows into PNG order copied twice.

    Pillow treats an image on a shared buffer as read-only and copies it on the first drawing;
    this one is marked writable (the buffer is ours and mutable). Should a Pillow version copy
    it anyway, :meth:`encode` sees that the image no longer holds the rows and encodes the
    image itself (:func:`encode_palette_png`): the file is right either way.
    """

    def __init__(self, rows: bytes | bytearray, size: tuple[int, int], palette: bytes) -> None:
        self._rows = bytearray(rows)
        if len(self._rows) != size[1] * (size[0] + 1) + 1:
            raise ValueError(f"RowImage: {len(rows)} bytes are not the rows of a {size} image")
        self.image = _mapped(self._rows, size)
        self.image.readonly = False  # drawn on in place (see the class docstring)
        self.image.putpalette(palette)
        self._core = self.image.im

    def encode(self, level: int) -> bytes:
        """PNG bytes of :attr:`image` as drawn, at zlib-ng ``level`` (the same bytes as
        :func:`encode_palette_png` of the image)."""
        if self.image.im is not self._core or "transparency" in self.image.info:
            return encode_palette_png(self.image, level)
        return _png(self.image, self._rows, level)


def _png(img: Image.Image, rows: bytearray, level: int) -> bytes:
    """The PNG file of ``img`` whose :func:`filtered_rows` are ``rows``."""
    deflate = zlib_ng.compressobj(level, zlib_ng.DEFLATED, 15, 9)
    data = deflate.compress(memoryview(rows)[:-1]) + deflate.flush()
    return b"".join((_header(img), _chunk(b"IDAT", data), _chunk(b"IEND", b"")))


def encode_palette_png(img: Image.Image, level: int) -> bytes:
    """PNG bytes of a palette image, deflated by zlib-ng at ``level`` (0-9; deterministic for
    equal input and zlib-ng version).

    Raises:
        ValueError: ``img`` is not an 8-bit palette ("P") image, or has a transparent colour
            (scene images have none; Pillow's encoder writes those).
    """
    if img.mode != "P" or "transparency" in img.info:
        raise ValueError(
            f"encode_palette_png: expected an opaque palette (P) image, got mode {img.mode}"
            + (" with transparency" if "transparency" in img.info else "")
        )
    img.load()
    return _png(img, filtered_rows(img), level)
