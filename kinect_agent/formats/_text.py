"""Reading a text recording the way users' files come: plain or gzip, UTF-8 with or without a BOM, UTF-16 from
Windows tools, CRLF / LF / CR line ends. Binary data and broken gzip streams are refused naming the file."""

from __future__ import annotations

import codecs
import re
import zlib
from pathlib import Path

from kinect_agent.errors import FormatError

GZIP_MAGIC = b"\x1f\x8b"
MAX_TEXT_BYTES = 1 << 30  # a decompressed recording larger than this (1 GiB) is refused, not read into memory
_UTF16_BOMS = (codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)
_DECIMAL = re.compile(r"[-+]?\d*\.(\d+)")
_INTEGER = re.compile(r"[-+]?\d+")
_NUMBERISH = re.compile(r"[-+.\d]|nan|inf", re.IGNORECASE)
_FIELDS = re.compile(r"[\s,;]+")


def read_text(path: str | Path) -> str:
    """Returns the whole text of the file at path: gunzipped when it starts with the gzip magic (whatever its name),
    BOM removed, UTF-16 decoded when it has a UTF-16 BOM, else UTF-8 (undecodable bytes become U+FFFD, so Latin-1
    comments pass and the reader names the line where a number is wrong). Raises FormatError on a NUL byte in
    UTF-8 text (a binary file), a corrupt or cut-short gzip stream, or a file that cannot be opened."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise FormatError(path, f"cannot read the file: {exc.strerror or exc}") from None
    if data.startswith(GZIP_MAGIC):
        data = _gunzip(path, data)
    if data.startswith(_UTF16_BOMS):
        try:
            return data.decode("utf-16")
        except UnicodeDecodeError as exc:
            raise FormatError(path, f"broken UTF-16 text at byte offset {exc.start}") from None
    nul = data.find(b"\0")
    if nul >= 0:
        raise FormatError(path, f"binary data (a NUL byte at byte offset {nul}): expected a text file")
    return data.decode("utf-8-sig", errors="replace")


def read_lines(path: str | Path) -> list[str]:
    """Returns the file's lines (read_text), line i at index i - 1, without their line ends (CRLF, LF or CR).

    Raises FormatError when the file was cut inside its last number (cut_inside_number)."""
    text = read_text(path)
    if "\r" in text:
        text = text.replace("\r\n", "\n") if "\n" in text else text.replace("\r", "\n")
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    elif cut_inside_number(lines):
        raise FormatError(path, "the last line ends inside a number, with fewer decimals than the lines before "
                          "(file truncated?)", len(lines))  # fmt: skip
    return lines


def last_content_line(lines: list[str]) -> int:
    """Returns the index of the last line that is not blank (where a cut-short file shows), -1 when all are."""
    return max((i for i, line in enumerate(lines) if line.strip()), default=-1)


def cut_inside_number(lines: list[str]) -> bool:
    """True when the last line (of a file without a final line end) ends in a number with fewer decimals than every
    number of the (at least 3, at most 5) lines before it, all written with one fixed count of decimals (as %.6f
    writers do): the file was cut while that number was being written. Files whose numbers have varying decimals
    (%g, shortest round-trip, exponents) are not judged."""
    previous = [line for line in lines[-6:-1] if line.strip()]
    if len(previous) < 3 or not lines[-1].strip():
        return False
    counts = set()
    for line in previous:
        fields = _FIELDS.split(line.strip())
        if _DECIMAL.fullmatch(fields[-1]) is None:
            return False
        for field in fields:
            match = _DECIMAL.fullmatch(field)
            if match is not None:
                counts.add(len(match.group(1)))
            elif _INTEGER.fullmatch(field) is None and _NUMBERISH.match(field):
                return False  # an exponent, nan ...: not a fixed-decimals writer
    if len(counts) != 1:
        return False
    last = _DECIMAL.fullmatch(_FIELDS.split(lines[-1].strip())[-1])
    return last is None or len(last.group(1)) < counts.pop()


def decoded_head(head: bytes) -> bytes:
    """Returns the first bytes of a file as UTF-8 text bytes for the format sniffers: gunzipped as far as they go,
    BOM removed, UTF-16 converted; other bytes unchanged."""
    if head.startswith(GZIP_MAGIC):
        try:
            head = zlib.decompressobj(wbits=31).decompress(head, 1 << 16)
        except zlib.error:
            return head
    if head.startswith(_UTF16_BOMS):
        even = head[: len(head) // 2 * 2]
        return even.decode("utf-16", errors="replace").encode("utf-8")
    return head.removeprefix(codecs.BOM_UTF8)


def _gunzip(path: Path, data: bytes) -> bytes:
    """Returns the decompressed bytes of every gzip member in data; FormatError when corrupt, cut short or too big."""
    out: list[bytes] = []
    size = 0
    rest = data
    while rest:
        stream = zlib.decompressobj(wbits=31)
        try:
            chunk = stream.decompress(rest, MAX_TEXT_BYTES + 1 - size)
        except zlib.error as exc:
            raise FormatError(path, f"corrupt gzip data: {exc}") from None
        size += len(chunk)
        if size > MAX_TEXT_BYTES:
            raise FormatError(path, f"gzip data decompresses to more than {MAX_TEXT_BYTES} bytes")
        if not stream.eof:
            raise FormatError(path, f"gzip data ends at byte offset {len(data)} before its end (file truncated?)")
        out.append(chunk)
        rest = stream.unused_data.lstrip(b"\0")  # gzip allows members back to back (and padding)
        if rest and not rest.startswith(GZIP_MAGIC):
            raise FormatError(path, f"unexpected bytes after the gzip data at byte offset {len(data) - len(rest)}")
    return b"".join(out)
