"""A minimal PNG encoder (stdlib zlib): what an env's ``render()`` gives as an RGB or RGBA
array becomes a file that browsers and the Rerun viewer decode, with no imaging library."""

from __future__ import annotations

import struct
import zlib
from typing import Any, Tuple

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
JPEG_SIGNATURE = b"\xff\xd8\xff"


def _chunk(kind: bytes, data: bytes) -> bytes:
    crc = zlib.crc32(kind + data) & 0xFFFFFFFF
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", crc)


def encode_png(pixels: Any, level: int = 3) -> Tuple[bytes, int, int]:
    """PNG bytes, width and height of ``pixels``: an ``H x W x 3`` (RGB) or ``H x W x 4``
    (RGBA) array of uint8 (NumPy, or nested sequences), or ``H x W`` grey."""
    np: Any
    try:
        import numpy as np
    except ImportError:  # pragma: no cover - Gymnasium brings NumPy
        np = None
    if np is not None:
        arr = np.ascontiguousarray(np.asarray(pixels, dtype=np.uint8))
        if arr.ndim == 2:
            arr = arr[:, :, None]
        if arr.ndim != 3 or arr.shape[2] not in (1, 3, 4):
            raise ValueError(f"a frame must be H x W x 3 or 4 (or H x W), got shape {arr.shape}")
        height, width, channels = arr.shape
        rows = np.zeros((height, 1 + width * channels), dtype=np.uint8)
        rows[:, 1:] = arr.reshape(height, width * channels)
        raw = rows.tobytes()
    else:  # pragma: no cover
        height, width = len(pixels), len(pixels[0])
        channels = len(pixels[0][0])
        raw = b"".join(b"\x00" + bytes(v for px in row for v in px) for row in pixels)
    colour = {1: 0, 3: 2, 4: 6}[channels]
    header = struct.pack(">IIBBBBB", width, height, 8, colour, 0, 0, 0)
    data = (
        PNG_SIGNATURE
        + _chunk(b"IHDR", header)
        + _chunk(b"IDAT", zlib.compress(raw, level))
        + _chunk(b"IEND", b"")
    )
    return data, width, height


def frame_of(rendered: Any) -> Tuple[str, bytes, int, int]:
    """``(format, bytes, width, height)`` of what ``render()`` returned: an array (encoded as
    PNG), or a PNG or JPEG file's bytes as they are (width and height read from the file)."""
    if isinstance(rendered, (bytes, bytearray, memoryview)):
        data = bytes(rendered)
        if data.startswith(PNG_SIGNATURE):
            width, height = struct.unpack(">II", data[16:24])
            return "png", data, width, height
        if data.startswith(JPEG_SIGNATURE):
            width, height = _jpeg_size(data)
            return "jpeg", data, width, height
        raise ValueError("render() returned bytes that are neither PNG nor JPEG")
    data, width, height = encode_png(rendered)
    return "png", data, width, height


def _jpeg_size(data: bytes) -> Tuple[int, int]:
    """Width and height from a JPEG's start-of-frame marker (0, 0 if there is none)."""
    i = 2
    while i + 9 < len(data):
        if data[i] != 0xFF:
            i += 1
            continue
        marker = data[i + 1]
        (length,) = struct.unpack(">H", data[i + 2 : i + 4])
        if marker in (0xC0, 0xC1, 0xC2):
            height, width = struct.unpack(">HH", data[i + 5 : i + 9])
            return width, height
        i += 2 + length
    return 0, 0
