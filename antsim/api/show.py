"""How a result shows itself and its numbers: astropy Quantities at the boundary, a short
table in a notebook (``_repr_html_``) and at a prompt (``__repr__``), figures kept in memory.

Every angle a result returns is an :class:`astropy.units.Quantity` (arcsec); every angle a
function takes may be a Quantity of angle or a plain number of arcsec. The documents
(``to_json()``) are the files' own, plain numbers with the unit in the key.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import astropy.units as u
import numpy as np

from antsim.figures.html import format_number, table_html
from antsim.figures.style import in_memory
from controller.errors import InputError

if TYPE_CHECKING:
    from astropy.table import QTable
    from astropy.units import Quantity

    from antsim.figures.html import Table
    from antsim.figures.style import FigureFile

__all__ = ["ShownAsTable", "arcsec", "as_arcsec", "drawn", "figure_of", "formatted", "table_text"]


def arcsec(value: Any) -> Quantity | None:
    """``value`` (arcsec: a number or an array) as a Quantity; None and NaN stay None."""
    if value is None:
        return None
    if np.ndim(value) == 0 and not math.isfinite(float(value)):
        return None
    return np.asarray(value, dtype=float) * u.arcsec


def as_arcsec(value: Any, where: str, field: str) -> float:
    """An angle given to the API: a Quantity of angle, or a plain number of arcsec."""
    if isinstance(value, u.Quantity):
        if not value.unit.is_equivalent(u.arcsec) or not value.isscalar:
            raise InputError(where, field, str(value), "must be one angle (arcsec, deg, ...)")
        return float(value.to_value(u.arcsec))
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(where, field, value,
                         "must be an angle: an astropy Quantity or a number of arcsec")
    return float(value)


def formatted(table: QTable, number_format: str) -> QTable:
    """``table`` with its number columns (all but the first) printed at ``number_format``;
    the values are kept as they are."""
    for name in table.colnames[1:]:
        table[name].info.format = number_format
    return table


def _cell(value: Any, spec: str) -> str:
    """A cell of a text table as the HTML one shows it (a dash for nothing)."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    if isinstance(value, float):
        return format_number(value, spec)
    return str(value)


def table_text(table: Table) -> str:
    """``table`` as aligned text: its caption, the header and the rows (numbers at the
    formats of the HTML table, right-aligned)."""
    rows = [[_cell(v, (table.column_formats[j] if j < len(table.column_formats) else None)
                   or table.number_format) for j, v in enumerate(row)] for row in table.rows]
    header = [str(h) for h in table.header]
    widths = [max([len(header[j])] + [len(r[j]) for r in rows]) for j in range(len(header))]
    numeric = [any(isinstance(row[j], int | float) and not isinstance(row[j], bool)
                   for row in table.rows) for j in range(len(header))]

    def line(cells: Sequence[str]) -> str:
        return "  ".join(c.rjust(w) if num else c.ljust(w)
                         for c, w, num in zip(cells, widths, numeric, strict=True)).rstrip()

    return "\n".join([table.caption, line(header), *(line(r) for r in rows)])


class ShownAsTable:
    """A result shown as its :meth:`_table`: HTML in a notebook, text at a prompt."""

    def _table(self) -> Table:
        raise NotImplementedError

    def _repr_html_(self) -> str:
        return table_html(self._table())

    def __repr__(self) -> str:
        return table_text(self._table())


def drawn(draw: Callable[[Path], Sequence[FigureFile]]) -> dict[str, Any]:
    """The figures ``draw(directory)`` makes, drawn in memory (nothing written), by the name
    of the file each would have been (its stem: "fig1_sky", "diagnose_quiver", ...)."""
    with in_memory():
        files = draw(Path("figures"))
    return {Path(f.path).stem: f.figure for f in files}


def figure_of(figures: Mapping[str, Any], name: str, what: str) -> Any:
    """The figure ``name`` of ``figures``, or a ValueError naming those there are."""
    if name not in figures:
        raise ValueError(f"{what} has no figure {name!r}; it has {', '.join(figures)}")
    return figures[name]
