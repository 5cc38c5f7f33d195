"""Errors that the CLI reports as one line with exit status 2, and the text-file opener
that turns binary content into such an error."""
from __future__ import annotations

import contextlib
import io
from pathlib import Path


class InputError(ValueError):
    """Bad user input (file content, option value). The message is shown as is."""


@contextlib.contextmanager
def text_file(path, source: str, newline: str | None = None):
    """A UTF-8 text file opened for reading (BOM skipped); binary content is refused with
    ``FILE:LINE:1: not a ... text file`` naming the byte offset, not a codec message."""
    data = Path(path).read_bytes()
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise InputError(f"{source}:{line}:1: not a UTF-8 text file (byte "
                         f"0x{data[exc.start]:02x} at offset {exc.start})") from None
    if "\x00" in text:
        line = text.count("\n", 0, text.index("\x00")) + 1
        raise InputError(f"{source}:{line}:1: not a text file (NUL byte)")
    yield io.StringIO(text, newline=newline)
