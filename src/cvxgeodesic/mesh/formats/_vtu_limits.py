"""The bounds of :mod:`._limits` for VTU (VTK XML) files, checked before meshio reads one.

- Each ``<Piece>``'s ``NumberOfPoints`` and ``NumberOfCells`` must fit the file (:func:`._bounds.check_counts`;
  compressed files at :data:`._bounds.MAX_COMPRESSION`:1).
- In a compressed file (``compressor="vtkZLibDataCompressor"`` or LZMA), every binary array, inline or appended
  (base64 or raw), is refused when its compressed-block header declares more bytes than its counts allow, before
  anything is inflated; else it is inflated here once, block by block and :data:`_CHUNK` bytes at a time, and
  refused as soon as a block inflates to more than its header declares. What an array may hold: a point array
  (``Points``, ``PointData``) ``NumberOfPoints × components × item size`` bytes, a cell array (``CellData``,
  ``offsets``, ``types``, ``faceoffsets``) ``NumberOfCells × components × item size``, any other
  (``connectivity``, ``faces``, ``FieldData``) what is left of :data:`._bounds.MAX_COMPRESSION` times the file's
  size for all the arrays together. meshio inflates every block whole and concatenates the blocks; this check
  needs the memory of one compressed array.
"""

from __future__ import annotations

import base64
import binascii
import itertools
import lzma
import math
import re
import zlib
from pathlib import Path
from typing import Literal

from ._bounds import MAX_COMPRESSION, POINT_BYTES, Count, FileBytes, check_counts
from ._common import format_error

__all__ = ["check_vtu"]

_TAG = re.compile(rb"<(/?)(Piece|Points|Cells|PointData|CellData|FieldData|DataArray)\b([^>]*)>")
_ATTR = re.compile(rb'([\w:]+)\s*=\s*"([^"]*)"')
_ITEM = {"Int8": 1, "UInt8": 1, "Int16": 2, "UInt16": 2, "Int32": 4, "UInt32": 4, "Int64": 8, "UInt64": 8,
         "Float32": 4, "Float64": 8}
_CODECS = {"vtkZLibDataCompressor": "zlib", "vtkLZMADataCompressor": "lzma"}
_CELL_ARRAYS = ("offsets", "types", "faceoffsets")
#: bytes inflated at a time
_CHUNK = 1 << 20

_Order = Literal["little", "big"]


class _Refused(Exception):
    """An array past its bound (the message says why)."""


def _attrs(text: bytes) -> dict[str, str]:
    return {k.decode(): v.decode("latin-1") for k, v in _ATTR.findall(text)}


def _int(value: str | None) -> int:
    return int(value) if value is not None and value.strip().isdigit() else 0


def check_vtu(path: Path, data: FileBytes) -> None:
    """Check a VTU file's counts and compressed arrays (the module's docstring); MeshFormatError past a bound."""
    head = re.search(rb"<VTKFile\b([^>]*)>", data[:65536])
    if head is None:
        return  # not a VTU: meshio says so
    root = _attrs(head.group(1))
    codec = _CODECS.get(root.get("compressor", ""))
    order: _Order = "big" if root.get("byte_order") == "BigEndian" else "little"
    layout = (8 if root.get("header_type") == "UInt64" else 4, order)
    appended = _appended(data)
    stop = appended[2] if appended else len(data)
    size, budget = len(data), len(data) * MAX_COMPRESSION
    section, n, c, piece = "", 0, 0, -1
    for m in _TAG.finditer(data, 0, stop):
        closing, tag, attrs = m.group(1), m.group(2).decode(), _attrs(m.group(3))
        if tag == "DataArray":
            if codec and not closing:
                where = f"DataArray {attrs.get('Name', section)!r} (piece {piece})"
                limit, why = _limit(section, attrs, n, c, budget)
                try:
                    blocks = _blocks(data, m, attrs, appended, layout)
                    declared = sum(size for size, _ in blocks)
                    if declared > limit:  # at the header: nothing inflated yet
                        raise _Refused(f"declares {declared} bytes inflated (its compressed-block header), more than "
                                       f"the {limit} bytes {why}")
                    budget -= _inflated(blocks, codec)
                except _Refused as exc:
                    raise format_error(path, f"{where} {exc}; refused before reading it") from None
        elif closing:
            section = ""
        elif tag == "Piece":
            piece, n, c = piece + 1, _int(attrs.get("NumberOfPoints")), _int(attrs.get("NumberOfCells"))
            ratio = MAX_COMPRESSION if codec else 1
            check_counts(path, size, [Count(f"points (NumberOfPoints of piece {piece})", n, POINT_BYTES, ratio),
                                      Count(f"cells (NumberOfCells of piece {piece})", c, 1, ratio)])
        else:
            section = tag


def _limit(section: str, attrs: dict[str, str], n: int, c: int, budget: int) -> tuple[int, str]:
    """The most bytes an array may inflate to, and why (for the message)."""
    item, nc = _ITEM.get(attrs.get("type", ""), 8), max(1, _int(attrs.get("NumberOfComponents", "1")))
    if section in ("Points", "PointData"):
        return n * nc * item, f"NumberOfPoints {n} allows ({n} × {nc} component(s) × {item} bytes)"
    if section == "CellData" or (section == "Cells" and attrs.get("Name") in _CELL_ARRAYS):
        return c * nc * item, f"NumberOfCells {c} allows ({c} × {nc} component(s) × {item} bytes)"
    return budget, f"the file's size allows (all arrays together at most {MAX_COMPRESSION} times its size)"


def _appended(data: FileBytes) -> tuple[int, bool, int] | None:
    """(first byte after the ``_`` that starts the appended data, raw encoding?, where ``<AppendedData`` starts)."""
    m = re.search(rb"<AppendedData\b([^>]*)>", data)
    if m is None:
        return None
    start = data.find(b"_", m.end())
    return (start + 1 if start >= 0 else len(data)), _attrs(m.group(1)).get("encoding") == "raw", m.start()


def _blocks(data: FileBytes, m: re.Match, attrs: dict[str, str], appended: tuple[int, bool, int] | None,
            layout: tuple[int, _Order]) -> list[tuple[int, bytes]]:
    """The compressed blocks of one array (:func:`_split_blocks`), each with the bytes its header says it inflates
    to."""
    if attrs.get("format") == "binary":
        if m.group(3).rstrip().endswith(b"/"):  # <DataArray .../>: no data
            return []
        end = data.find(b"</DataArray>", m.end())
        return _split_blocks(data[m.end():end if end >= 0 else len(data)].strip(), layout, raw=False)
    if attrs.get("format") != "appended" or appended is None:
        return []
    return _split_blocks(memoryview(data)[appended[0] + _int(attrs.get("offset")):], layout, raw=appended[1])


def _header(raw: bytes, hs: int, order: _Order) -> list[int]:
    return [int.from_bytes(raw[i:i + hs], order) for i in range(0, len(raw) - hs + 1, hs)]


def _chars(nbytes: int) -> int:
    """base64 characters of ``nbytes`` bytes."""
    return 4 * math.ceil(nbytes / 3)


def _split_blocks(text, layout: tuple[int, _Order], *, raw: bool) -> list[tuple[int, bytes]]:
    """``(inflated size, compressed block)`` of each block of a raw or a base64 array (base64: its header and its
    blocks are encoded apart, as VTK writes them).

    VTK's header is ``num_blocks, block size, last block size, compressed sizes...``: every block inflates to the
    block size but the last, which inflates to the last block size (0: the block size, a full block).
    """
    hs, order = layout
    span = (lambda nbytes: nbytes) if raw else _chars  # the characters of so many bytes
    decode = bytes if raw else (lambda t: base64.b64decode(bytes(t)))
    try:
        first = _header(decode(text[:span(hs)]), hs, order)
        nb = first[0] if first else 0
        hc = span((3 + nb) * hs)
        if not first or hc > len(text):
            raise _Refused("has a compressed-block header cut short")
        head = _header(decode(text[:hc]), hs, order)
        sizes = head[3:3 + nb]
        body = decode(text[hc:hc + span(sum(sizes))])
    except binascii.Error as exc:
        raise _Refused(f"is not valid base64 ({exc})") from None
    if sum(sizes) > len(body):
        raise _Refused("has compressed blocks cut short")
    full, last = head[1], head[2] or head[1]
    ends = [0, *itertools.accumulate(sizes)]
    return [(last if k == nb - 1 else full, body[ends[k]:ends[k + 1]]) for k in range(len(sizes))]


def _inflated(blocks: list[tuple[int, bytes]], codec: str) -> int:
    """The bytes the blocks inflate to; _Refused as soon as a block inflates to more than its header declares."""
    total = 0
    for k, (limit, block) in enumerate(blocks):
        done = 0
        d = zlib.decompressobj() if codec == "zlib" else lzma.LZMADecompressor()
        buf = block
        try:
            while True:
                out = d.decompress(buf, _CHUNK)
                done += len(out)
                if done > limit:
                    raise _Refused(f"has a block (block {k}) that inflates to more than the {limit} bytes its "
                                   "compressed-block header declares")
                if codec == "zlib":
                    buf = d.unconsumed_tail  # type: ignore[union-attr]
                    if d.eof or (not buf and len(out) < _CHUNK):
                        break
                else:
                    buf = b""
                    if d.eof or d.needs_input:  # type: ignore[union-attr]
                        break
        except (zlib.error, lzma.LZMAError) as exc:
            raise _Refused(f"has corrupt compressed data ({exc})") from None
        total += done
    return total
