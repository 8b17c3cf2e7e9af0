"""The rule of the reader bounds (:mod:`._limits`): a count must fit the file's size, at a stated compression ratio."""

from __future__ import annotations

import mmap
from collections.abc import Iterable
from pathlib import Path
from typing import NamedTuple, TypeAlias

from ._common import format_error

__all__ = ["MAX_COMPRESSION", "POINT_BYTES", "Count", "FileBytes", "check_counts"]

#: A file's bytes as the checks scan them: mapped (no copy), or read where the file system cannot map it.
FileBytes: TypeAlias = mmap.mmap | bytes

#: zlib's largest compression ratio, about 1032:1 (a deflate match of 258 bytes costs at least 2 bits, RFC 1951);
#: the bound also applies to LZMA-compressed VTU files, whose ratio could be higher (zeros: 6800:1; no mesh is that).
MAX_COMPRESSION = 1032
#: The fewest bytes a point takes in any format (one per coordinate: 3 UInt8 values); 1 byte for anything else.
POINT_BYTES = 3


class Count(NamedTuple):
    """A count of a header: what is counted (for the message), the count, the fewest bytes one item takes in the
    file, and the compression ratio the file may have (1: uncompressed)."""

    what: str
    n: int
    per: int = 1
    ratio: int = 1


def check_counts(path: Path, size: int, counts: Iterable[Count]) -> None:
    """Refuse a count that a file of ``size`` bytes cannot hold: ``n × per > size × ratio``.

    Raises
    ------
    MeshFormatError
        ``"<path>: the header declares <count> <what>, more than a file of <size> bytes can hold (at most
        <limit>: <per> byte(s) each, <uncompressed | compressed at most 1032:1>)"``.
    """
    for c in counts:
        if c.n * c.per > size * c.ratio:
            how = f"compressed at most {c.ratio}:1" if c.ratio > 1 else "uncompressed"
            raise format_error(path, f"the header declares {c.n} {c.what}, more than a file of {size} bytes can "
                                     f"hold (at most {size * c.ratio // c.per}: {c.per} byte(s) each, {how})")
