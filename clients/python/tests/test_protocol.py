"""The framing and the PNG encoder, without a network."""

from __future__ import annotations

import io
import struct
import zlib

import numpy as np
import pytest

from dualrep.env.png import encode_png, frame_of
from dualrep.env.protocol import ProtocolError, read_message, write_message


def test_a_message_is_a_big_endian_length_and_json_then_its_attachment() -> None:
    out = io.BytesIO()
    write_message(out, {"type": "step", "obs": [1.5, -2.0]}, attachment=b"\x89PNGxyz")
    raw = out.getvalue()
    (n,) = struct.unpack(">I", raw[:4])
    assert raw[4 : 4 + n] == b'{"type":"step","obs":[1.5,-2.0]}'
    assert raw[4 + n :] == b"\x89PNGxyz"
    assert read_message(io.BytesIO(raw[: 4 + n])) == {"type": "step", "obs": [1.5, -2.0]}


def test_the_end_of_the_stream_between_messages_is_none_and_inside_one_an_error() -> None:
    assert read_message(io.BytesIO(b"")) is None
    with pytest.raises(ProtocolError, match="inside a message"):
        read_message(io.BytesIO(struct.pack(">I", 10) + b'{"ty'))
    with pytest.raises(ProtocolError, match="not JSON"):
        read_message(io.BytesIO(struct.pack(">I", 3) + b"{{{"))
    with pytest.raises(ProtocolError, match='"type"'):
        read_message(io.BytesIO(struct.pack(">I", 2) + b"[]"))
    with pytest.raises(ProtocolError, match="at most"):
        read_message(io.BytesIO(struct.pack(">I", 1 << 30)))


def test_non_finite_numbers_are_refused_rather_than_sent_as_invalid_json() -> None:
    with pytest.raises(ValueError):
        write_message(io.BytesIO(), {"type": "step", "reward": float("nan")})


def _decode_png(data: bytes) -> np.ndarray:
    """A tiny PNG reader for what encode_png writes (8-bit, filter 0, one IDAT)."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, chunks = 8, {}
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + length]
        (crc,) = struct.unpack(">I", data[pos + 8 + length : pos + 12 + length])
        assert crc == zlib.crc32(kind + body) & 0xFFFFFFFF
        chunks[kind] = body
        pos += 12 + length
    width, height, depth, colour = struct.unpack(">IIBB", chunks[b"IHDR"][:10])
    assert depth == 8
    channels = {0: 1, 2: 3, 6: 4}[colour]
    rows = np.frombuffer(zlib.decompress(chunks[b"IDAT"]), dtype=np.uint8).reshape(height, 1 + width * channels)
    assert (rows[:, 0] == 0).all()
    return rows[:, 1:].reshape(height, width, channels)


def test_png_frames_decode_to_the_pixels_they_were_made_from() -> None:
    rng = np.random.default_rng(0)
    for shape in [(4, 5, 3), (3, 2, 4), (6, 7)]:
        pixels = rng.integers(0, 256, size=shape, dtype=np.uint8)
        data, width, height = encode_png(pixels)
        assert (width, height) == (shape[1], shape[0])
        back = _decode_png(data)
        assert (back.reshape(pixels.shape) == pixels).all()
    with pytest.raises(ValueError, match="H x W"):
        encode_png(np.zeros((2, 2, 2), dtype=np.uint8))


def test_encoded_files_pass_through_with_their_size() -> None:
    data, _, _ = encode_png(np.zeros((3, 8, 3), dtype=np.uint8))
    assert frame_of(data) == ("png", data, 8, 3)
    # A minimal JPEG header: SOI, then a SOF0 marker with height 2 and width 9.
    jpeg = b"\xff\xd8\xff\xc0\x00\x11\x08\x00\x02\x00\x09\x03" + b"\x00" * 12
    assert frame_of(jpeg)[0::2] == ("jpeg", 9)
    with pytest.raises(ValueError, match="neither PNG nor JPEG"):
        frame_of(b"GIF89a")
