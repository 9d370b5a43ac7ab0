"""Reading a URDF file once, and the text of exactly the bytes that were parsed.

:func:`read_bytes_once` opens the path once (non-blocking, so a FIFO cannot hang it), refuses
anything but a regular file and reads at most ``Limits.max_bytes`` + 1 bytes from that one open
file: what is parsed and what :attr:`Robot.urdf_text <kinengine.Robot.urdf_text>` shows are the same
bytes, even if the path is swapped for another file (or a link to /dev/zero) in between.
:func:`decode_xml` decodes them as XML says they are encoded (byte-order mark, else the
``encoding`` of the XML declaration, else UTF-8; UTF-16 without a mark is recognised by its first
characters) and rewrites the declaration's encoding to UTF-8, so the text re-encodes to UTF-8 and
parses to the same document (e.g. by the reference kinematics of ``kinengine verify``).
"""

from __future__ import annotations

import codecs
import os
import re
import stat

from ..errors import URDFError
from .limits import LIMITS, Limits

_NONBLOCKING = getattr(os, "O_NONBLOCK", 0)
_BOMS = (
    (codecs.BOM_UTF32_LE, "utf-32-le"),
    (codecs.BOM_UTF32_BE, "utf-32-be"),
    (codecs.BOM_UTF8, "utf-8"),
    (codecs.BOM_UTF16_LE, "utf-16-le"),
    (codecs.BOM_UTF16_BE, "utf-16-be"),
)
_DECLARED = re.compile(rb"""^<\?xml[^>]*?\sencoding\s*=\s*["']([A-Za-z][A-Za-z0-9._-]{0,39})["']""")
_DECLARATION = re.compile(r"""^(<\?xml[^>]*?\sencoding\s*=\s*)(["'])[A-Za-z][A-Za-z0-9._-]{0,39}\2""")


def read_bytes_once(path: str | os.PathLike[str], limits: Limits = LIMITS) -> tuple[str, bytes]:
    """(the path as text, the file's bytes), read from one open file descriptor; URDFError naming the
    path for a missing, unreadable, non-regular or too large file, or a bad path (too long, NUL)."""
    try:
        source = os.fspath(path)
    except TypeError:
        raise URDFError(f"expected a path to a .urdf file, got {type(path).__name__}") from None
    if isinstance(source, bytes):
        source = os.fsdecode(source)
    try:
        fd = os.open(source, os.O_RDONLY | _NONBLOCKING)
    except FileNotFoundError:
        raise URDFError("no such file", source=_short(source)) from None
    except (OSError, ValueError) as exc:  # ValueError: a NUL character in the path
        reason = getattr(exc, "strerror", None) or exc
        raise URDFError(f"cannot open the file: {reason}", source=_short(source)) from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            kind = "a directory" if stat.S_ISDIR(info.st_mode) else "a device, FIFO or socket"
            raise URDFError(f"not a regular file ({kind})", source=source)
        if info.st_size > limits.max_bytes:
            raise URDFError(
                f"the file is {info.st_size} bytes, more than Limits.max_bytes = {limits.max_bytes}",
                source=source,
            )
        chunks, left = [], limits.max_bytes + 1
        while left > 0:
            chunk = os.read(fd, min(left, 1 << 20))
            if not chunk:
                break
            chunks.append(chunk)
            left -= len(chunk)
        data = b"".join(chunks)
    except OSError as exc:
        raise URDFError(f"cannot read the file: {exc.strerror}", source=source) from None
    finally:
        os.close(fd)
    if len(data) > limits.max_bytes:
        raise URDFError(
            f"the file grew past Limits.max_bytes = {limits.max_bytes} while it was read", source=source
        )
    return source, data


def xml_encoding(data: bytes) -> str:
    """The encoding XML's rules give ``data``: its byte-order mark, else its declaration, else UTF-8."""
    for bom, name in _BOMS:
        if data.startswith(bom):
            return name
    if data.startswith(b"<\x00?\x00"):
        return "utf-16-le"
    if data.startswith(b"\x00<\x00?"):
        return "utf-16-be"
    match = _DECLARED.match(data)
    return match.group(1).decode("ascii") if match else "utf-8"


def decode_xml(data: bytes) -> str:
    """``data`` decoded as XML declares (see the module doc), without a byte-order mark, its declaration's
    encoding rewritten to UTF-8; undecodable bytes (which the parser would have refused) become U+FFFD."""
    name = xml_encoding(data)
    try:
        codec = codecs.lookup(name).name
    except LookupError:
        codec = "utf-8"
    text = data.decode(codec, errors="replace")
    if text.startswith("\ufeff"):
        text = text[1:]
    return _DECLARATION.sub(lambda m: f"{m.group(1)}{m.group(2)}UTF-8{m.group(2)}", text, count=1)


def _short(path: str) -> str:
    return path if len(path) <= 120 else path[:60] + "..." + path[-40:]


__all__ = ["decode_xml", "read_bytes_once", "xml_encoding"]
