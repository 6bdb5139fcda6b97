"""Files that name W1..W10 as antsim did before it had the 1990 report's equations.

Until the report was at hand its section II was not available, and W1..W10 were a reconstruction
(the same ten functions in another order, each with the same sign):

    reconstruction  W1  W2   W3  W4  W5  W6  W7  W8  W9  W10
    the report's    W6  W10  W9  W4  W5  W1  W2  W3  W8  W7

e.g. the reconstruction's W1 (dA = W1, an azimuth encoder zero) is the report's W6. Files
written since say which definition their W terms follow (``W_TERMS_KEY`` in a JSON document
or in the recordings' model metadata, ``W_TERMS_COMMENT`` in a ``.mod`` file); a file that
names W terms without it was written by the reconstruction, and its terms are renamed to the
report's: the same functions with the same values, so the model points exactly as before
(tested). Each rename is announced by one :class:`RelabelledTermsWarning`, which the command
line prints as a one-line note.
"""

from __future__ import annotations

import re
import warnings
from collections.abc import Iterable, Mapping

__all__ = ["RECONSTRUCTED_TO_REPORT", "W_TERMS", "W_TERMS_COMMENT", "W_TERMS_KEY",
           "RelabelledTermsWarning", "names_w_terms", "relabel_reconstructed", "w_terms_marker"]

#: what the W terms of files written now follow
W_TERMS = "Ghigo 1990 (NRAO EDIR 288) section II"
#: the key that carries :data:`W_TERMS` in JSON documents and the recordings' model metadata
W_TERMS_KEY = "w_terms"
#: the comment line that carries it in a ``.mod`` file
W_TERMS_COMMENT = f"! W1..W10: {W_TERMS}"

#: the reconstruction's name of each function -> the report's name of the same function
RECONSTRUCTED_TO_REPORT: dict[str, str] = {
    "W1": "W6", "W2": "W10", "W3": "W9", "W4": "W4", "W5": "W5",
    "W6": "W1", "W7": "W2", "W8": "W3", "W9": "W8", "W10": "W7",
}

_W = re.compile(r"^W([1-9]|10)$")


class RelabelledTermsWarning(UserWarning):
    """A file's W terms were renamed from the reconstruction to the report's (a note)."""


def names_w_terms(names: Iterable[str]) -> bool:
    """Whether any of ``names`` is one of W1..W10."""
    return any(_W.match(str(n).strip().upper()) for n in names)


def w_terms_marker(names: Iterable[str]) -> dict[str, str]:
    """``{W_TERMS_KEY: W_TERMS}`` for a model that names W terms, else ``{}``."""
    return {W_TERMS_KEY: W_TERMS} if names_w_terms(names) else {}


def relabel_reconstructed(terms: Mapping[str, float], where: str) -> dict[str, float]:
    """``terms`` (name -> value) of a file written without the marker, with its W terms
    renamed to the report's (other names unchanged), announced by one warning naming
    ``where``. Order follows the report's numbering for the W terms."""
    upper = {str(k).strip().upper(): v for k, v in terms.items()}
    renamed = {RECONSTRUCTED_TO_REPORT.get(k, k): v for k, v in upper.items()}
    moved = [f"{k}->{v}" for k, v in RECONSTRUCTED_TO_REPORT.items() if k in upper and k != v]
    warnings.warn(
        f"{where}: written before antsim followed the 1990 report's W1..W10 (it names no "
        f"'{W_TERMS_KEY}'); its W terms are renamed to the report's ({', '.join(moved)}): "
        "the same functions and values", RelabelledTermsWarning, stacklevel=3)
    return _in_report_order(renamed)


def _in_report_order(terms: dict[str, float]) -> dict[str, float]:
    """``terms`` with its W terms in the report's order, at the place of the first one."""
    order = {f"W{i}": i for i in range(1, 11)}
    ws = sorted((k for k in terms if k in order), key=order.__getitem__)
    out: dict[str, float] = {}
    for k, v in terms.items():
        if k not in order:
            out[k] = v
        elif ws:
            out.update({w: terms[w] for w in ws})
            ws = []
    return out
