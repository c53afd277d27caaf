"""The remote program protocol (version 1): newline-delimited JSON over TCP.

Shared by the server (:mod:`workcell.program.server`) and the Python client
(:mod:`workcell.client`); the document is ``docs/protocol.md``. One message is one line
of UTF-8 JSON ended by ``\\n``, at most :data:`MAX_MESSAGE_BYTES` bytes with the newline.
Requests are ``{"id", "command", "args"}``; replies ``{"id", "result"}`` or
``{"id", "error": {"type", "message"}}``. Numbers are JSON numbers (a non-finite float
is sent as null); arrays are lists (a 4x4 pose is 4 rows of 4).
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from workcell import errors
from workcell.errors import ProtocolError, WorkcellError

__all__ = [
    "DEFAULT_PORT",
    "MAX_MESSAGE_BYTES",
    "PROTOCOL",
    "VERSION",
    "ReplyTooLargeError",
    "Request",
    "decode_request",
    "encode",
    "encode_bounded",
    "error_class",
    "error_reply",
    "error_type",
    "to_jsonable",
]

PROTOCOL = "workcell"
VERSION = 1
MAX_MESSAGE_BYTES = 1 << 20  # 1 MiB: one line, newline included
DEFAULT_PORT = 5260


def to_jsonable(v: Any) -> Any:
    """``v`` as plain JSON values: arrays and tuples as lists, numpy scalars as numbers,
    non-finite floats as None, named tuples as objects."""
    if v is None or isinstance(v, (bool, str, int)):
        return v
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, np.ndarray):
        return to_jsonable(v.tolist())
    if isinstance(v, np.generic):
        return to_jsonable(v.item())
    if isinstance(v, dict):
        return {str(k): to_jsonable(x) for k, x in v.items()}
    if isinstance(v, tuple) and hasattr(v, "_asdict"):
        return to_jsonable(v._asdict())
    if isinstance(v, (list, tuple)):
        return [to_jsonable(x) for x in v]
    raise ProtocolError(f"cannot send a {type(v).__name__} as JSON")


def encode(message: dict[str, Any]) -> bytes:
    """One protocol line: compact JSON of ``message`` and a newline."""
    return json.dumps(to_jsonable(message), separators=(",", ":"), allow_nan=False).encode() + b"\n"


class ReplyTooLargeError(ProtocolError):
    """A reply went past the message bound while it was being encoded (``size``: bytes
    encoded when it stopped)."""

    def __init__(self, size: int, bound: int) -> None:
        super().__init__(
            f"the reply is over {size:,} bytes, over the {bound:,}-byte bound "
            "(the command ran; ask for less)"
        )
        self.size = size


_CHUNK = 4096  # numbers of an array encoded at a time


def _parts(v: Any) -> Iterator[str]:
    """The compact JSON of ``v`` (as :func:`encode` writes it) in pieces; a large array is
    converted a few thousand numbers at a time, never whole."""
    if isinstance(v, np.ndarray) and v.ndim >= 1 and v.size > _CHUNK:
        yield "["
        rows = max(1, _CHUNK // max(1, v[0].size))
        for k in range(0, len(v), rows):
            text = json.dumps(to_jsonable(v[k : k + rows]), separators=(",", ":"))
            yield ("," if k else "") + text[1:-1]
        yield "]"
    elif isinstance(v, dict):
        yield "{"
        for k, (key, x) in enumerate(v.items()):
            yield ("," if k else "") + json.dumps(str(key)) + ":"
            yield from _parts(x)
        yield "}"
    elif isinstance(v, tuple) and hasattr(v, "_asdict"):
        yield from _parts(v._asdict())
    elif isinstance(v, (list, tuple)):
        yield "["
        for k, x in enumerate(v):
            if k:
                yield ","
            yield from _parts(x)
        yield "]"
    else:
        yield json.dumps(to_jsonable(v), separators=(",", ":"), allow_nan=False)


def encode_bounded(message: dict[str, Any], bound: int = MAX_MESSAGE_BYTES) -> bytes:
    """:func:`encode`, stopping with :class:`ReplyTooLargeError` as soon as the line passes
    ``bound`` bytes (newline included): a huge result is never encoded whole."""
    out, size = [], 1
    for part in _parts(message):
        size += len(part)  # ASCII: json escapes every other character
        if size > bound:
            raise ReplyTooLargeError(size, bound)
        out.append(part)
    return "".join(out).encode() + b"\n"


@dataclass(frozen=True)
class Request:
    """A decoded request: its ``id`` (echoed in the reply), ``command`` and ``args``."""

    id: Any
    command: str
    args: dict[str, Any] | list[Any]


def decode_request(line: bytes) -> Request:
    """Decode one request line; ProtocolError says what is wrong (the id when known)."""
    try:
        text = line.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ProtocolError(f"a message must be UTF-8 text: {exc.reason}") from exc
    try:
        msg = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ProtocolError(f"malformed JSON at character {exc.pos + 1}: {exc.msg}") from exc
    except RecursionError:
        raise ProtocolError("malformed JSON: arrays or objects nested too deeply") from None
    except ValueError as exc:  # an integer of more than 4300 digits
        why = "an integer has more than 4300 digits" if "digits" in str(exc) else "a bad value"
        raise ProtocolError(f"malformed JSON: {why}") from None
    if not isinstance(msg, dict):
        raise ProtocolError(
            f'a request is a JSON object {{"id", "command", "args"}}, got {type(msg).__name__}'
        )
    rid = msg.get("id")
    if not (rid is None or (isinstance(rid, (str, int, float)) and not isinstance(rid, bool))):
        raise ProtocolError('"id" must be a string, a number or null')
    version = msg.get("version", VERSION)
    if version != VERSION:
        raise _with_id(
            ProtocolError(
                f"protocol version {_short(version)} unknown; this server speaks {VERSION}"
            ),
            rid,
        )
    command = msg.get("command")
    if not isinstance(command, str):
        raise _with_id(ProtocolError('"command" must be a string (a command name)'), rid)
    args = msg.get("args", {})
    if args is None:
        args = {}
    if not isinstance(args, (dict, list)):
        raise _with_id(
            ProtocolError('"args" must be an object (by name) or an array (in order)'), rid
        )
    return Request(rid, command, args)


def _short(v: Any) -> str:
    """``repr(v)``, at most 40 characters (a reply never echoes a client's long value)."""
    r = (
        repr(v)
        if not isinstance(v, int) or abs(v) < 10**30
        else f"a {len(str(abs(v)))}-digit number"
    )
    return r if len(r) <= 40 else r[:37] + "..."


def _with_id(exc: ProtocolError, rid: Any) -> ProtocolError:
    exc.request_id = rid  # type: ignore[attr-defined]
    return exc


def error_type(exc: BaseException) -> str:
    """The protocol's error type: the nearest class of :mod:`workcell.errors` (for a
    WorkcellError), else "InternalError"."""
    if isinstance(exc, WorkcellError):
        for cls in type(exc).__mro__:
            if cls.__module__ == errors.__name__:
                return cls.__name__
    return "InternalError"


def error_class(name: object) -> type[WorkcellError]:
    """The WorkcellError subclass named ``name`` (WorkcellError for an unknown name)."""
    cls = getattr(errors, name, None) if isinstance(name, str) else None
    if isinstance(cls, type) and issubclass(cls, WorkcellError):
        return cls
    return WorkcellError


def error_reply(rid: Any, exc: BaseException) -> dict[str, Any]:
    """The error reply to request ``rid`` for ``exc``."""
    return {"id": rid, "error": {"type": error_type(exc), "message": str(exc)}}
