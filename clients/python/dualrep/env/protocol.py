"""The bytes of dualrep's env protocol (docs/env-protocol.md in the repository).

Every message is a 4-byte big-endian length and that many bytes of one UTF-8 JSON object. A
reply that carries a rendered frame announces it in its ``frame`` field and the frame's encoded
bytes follow the message raw (``frame["bytes"]`` of them), so images cross without base64.
"""

from __future__ import annotations

import json
import struct
from typing import Any, BinaryIO, Dict, Optional

PROTOCOL = 1
#: Largest JSON message either side sends.
MAX_MESSAGE = 16 << 20

Message = Dict[str, Any]


class ProtocolError(Exception):
    """The other side sent something the protocol does not allow."""


def write_message(out: BinaryIO, message: Message, attachment: Optional[bytes] = None) -> None:
    """Write one message (and the raw bytes it announces, if any) and flush."""
    body = json.dumps(message, separators=(",", ":"), allow_nan=False).encode()
    if len(body) > MAX_MESSAGE:
        raise ProtocolError(f"a message of {len(body)} bytes (at most {MAX_MESSAGE})")
    out.write(struct.pack(">I", len(body)))
    out.write(body)
    if attachment is not None:
        out.write(attachment)
    out.flush()


def read_exact(inp: BinaryIO, n: int) -> Optional[bytes]:
    """``n`` bytes, or None if the stream ended before the first of them."""
    chunks = []
    left = n
    while left:
        chunk = inp.read(left)
        if not chunk:
            if left == n:
                return None
            raise ProtocolError(f"the connection closed inside a message ({n - left} of {n} bytes)")
        chunks.append(chunk)
        left -= len(chunk)
    return b"".join(chunks)


def read_message(inp: BinaryIO) -> Optional[Message]:
    """The next message, or None when the other side closed the connection between messages."""
    head = read_exact(inp, 4)
    if head is None:
        return None
    (length,) = struct.unpack(">I", head)
    if length > MAX_MESSAGE:
        raise ProtocolError(f"a message of {length} bytes (at most {MAX_MESSAGE})")
    body = read_exact(inp, length)
    if body is None:
        raise ProtocolError("the connection closed inside a message")
    try:
        message = json.loads(body)
    except ValueError as e:
        raise ProtocolError(f"not JSON: {e}") from None
    if not isinstance(message, dict) or not isinstance(message.get("type"), str):
        raise ProtocolError('expected a JSON object with a "type"')
    return message
