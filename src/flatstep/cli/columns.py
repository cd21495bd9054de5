"""The name column of the command line's fixed-width tables, sized to its longest entry."""
from __future__ import annotations

from collections.abc import Iterable


def name_width(names: Iterable[str], head: str, least: int) -> int:
    """The width of a table's first column: at least ``least``, and two more than the longest name or the head.

    Parameters
    ----------
    names : iterable of str
        The entries of the column (controller labels, law names).
    head : str
        The column's head.
    least : int
        The width a table of short names keeps.

    Returns
    -------
    int
        The width, so that every name is followed by at least two spaces and the other columns line up.
    """
    return max(least, max((len(n) for n in (head, *names)), default=0) + 2)
