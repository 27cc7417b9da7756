"""What the package's CSV readers (tactforce.inertia, tactforce.friction,
tactforce.audit) share: the header check and number parsing, with errors
that name the file, line and column as `tactforce` does."""

from __future__ import annotations

import csv
import math
from typing import Dict, Iterable, Iterator, List, Sequence, Tuple


class BadInput(Exception):
    """A file or flag the tools refuse (exit code 2); the message names the
    file, line and column, or the flag."""


def open_table(path: str, required: Iterable[str]) -> Tuple[Dict[str, int], Iterator[Tuple[int, List[str]]]]:
    """The header's column indices and an iterator of (line, row) for the
    rest; BadInput when the file is empty or misses a `required` column."""
    handle = open(path, newline="", encoding="utf-8")
    reader = csv.reader(handle)
    try:
        header = [name.strip() for name in next(reader)]
    except StopIteration:
        handle.close()
        raise BadInput(f"{path}: empty (no header)") from None
    col = {name: i for i, name in enumerate(header)}
    missing = [name for name in required if name not in col]
    if missing:
        handle.close()
        raise BadInput(f"{path}: missing column(s) {','.join(missing)}")

    def rows() -> Iterator[Tuple[int, List[str]]]:
        with handle:
            for line, row in enumerate(reader, start=2):
                if row and any(cell.strip() for cell in row):
                    yield line, row

    return col, rows()


def number(path: str, line: int, row: Sequence[str], col: Dict[str, int], name: str,
           allow_nan: bool = False) -> float:
    """Column `name` of `row` as a finite float (NaN too when `allow_nan`:
    an empty cell or 'nan', for readers that skip such rows)."""
    try:
        text = row[col[name]].strip()
    except IndexError:
        raise BadInput(f"{path}:{line}: column '{name}': missing") from None
    if allow_nan and text.lower() in ("", "nan"):
        return math.nan
    try:
        value = float(text)
    except ValueError:
        raise BadInput(f"{path}:{line}: column '{name}': not a number ('{text}')") from None
    if not math.isfinite(value):
        raise BadInput(f"{path}:{line}: column '{name}': not finite")
    return value
