"""Derived channels of a column map: a linear combination of columns, read without ``eval``.

A building often logs what a model needs in pieces: two heating circuits whose sum is the room's
heat input, a meter in kW, a sensor with a known offset. A column map writes such a channel as a
small expression (``Ph = { expr = "Ph1 + Ph2", unit = "kW" }``) or as a column with a ``scale`` and
an ``offset``. Either is a linear combination

.. math::

    x(t) = c_0 + \\sum_i k_i \\, \\mathrm{col}_i(t),

evaluated in the column map's unit before the conversion to SI (so a sum of two kW meters is one
kW channel). A sample is missing where any of its columns is missing: a sum over fewer circuits
would be a different input (the same rule as the mean of the surroundings, ``Tsd``).

The expression is untrusted text from a user's file. It is read by a tokenizer and a
recursive-descent reader of the grammar below (Aho, Lam, Sethi & Ullman 2006, ch. 2 and 4.4), never
by Python's ``eval``; it can only name columns and numbers, and its length and number of terms are
bounded::

    expr    := term (("+" | "-") term)*
    term    := ["-"] (number "*" column | column ["*" number] | column "/" number | number)
    column  := a name of letters, digits, "_" and "." that does not start with a digit,
               or any header in backquotes: `zone temp [degF]`

References
----------
Aho, A. V., Lam, M. S., Sethi, R. & Ullman, J. D. (2006). *Compilers: Principles, Techniques, and
Tools*, 2nd ed. Addison-Wesley.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from rczone.errors import DataError

#: Longest expression (characters) and most terms of one derived channel.
MAX_EXPRESSION_LENGTH = 500
MAX_TERMS = 32

_TOKEN = re.compile(
    r"\s*(?:"
    r"(?P<number>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"
    r"|`(?P<quoted>[^`]+)`"
    r"|(?P<name>[A-Za-z_][A-Za-z0-9_.]*)"
    r"|(?P<op>[-+*/])"
    r")"
)


@dataclass(frozen=True)
class Combination:
    """``offset + sum(factor * column)``: how a channel is computed from the table's columns.

    Attributes
    ----------
    terms : tuple of (str, float)
        Each column and its factor, in the order written (a column named twice is one term).
    offset : float
        Constant added, in the channel's declared unit.
    """

    terms: tuple[tuple[str, float], ...]
    offset: float = 0.0

    @property
    def columns(self) -> tuple[str, ...]:
        """The columns read."""
        return tuple(c for c, _ in self.terms)

    @property
    def is_plain(self) -> bool:
        """One column as it is (factor 1, no offset)."""
        return len(self.terms) == 1 and self.terms[0][1] == 1.0 and self.offset == 0.0

    def scaled(self, scale: float, offset: float) -> Combination:
        """``scale * self + offset``."""
        return Combination(tuple((c, scale * k) for c, k in self.terms), scale * self.offset + offset)


def _tokens(text: str, where: str) -> list[tuple[str, str]]:
    out, pos = [], 0
    while pos < len(text):
        if not text[pos:].strip():
            break
        m = _TOKEN.match(text, pos)
        if m is None or m.end() == pos:
            raise DataError(
                f"{where}: cannot read {text[pos:].strip()[:20]!r} in the expression {text!r}; write"
                " column names, numbers, + - * /, and a header with other characters in backquotes"
                " (`zone temp [degF]`)"
            )
        kind = m.lastgroup
        out.append(("name" if kind == "quoted" else kind, m.group(kind)))
        pos = m.end()
    return out


def _number(token: str, where: str) -> float:
    v = float(token)
    if not math.isfinite(v):
        raise DataError(f"{where}: the number {token} is not finite")
    return v


def _term(toks: list[tuple[str, str]], i: int, where: str, text: str) -> tuple[str | None, float, int]:
    """One term starting at ``toks[i]``: (column or None for a constant, factor, next index)."""

    def at(k: int) -> tuple[str, str]:
        return toks[k] if k < len(toks) else ("end", "")

    sign = 1.0
    if at(i) == ("op", "-"):
        sign, i = -1.0, i + 1
    kind, tok = at(i)
    if kind == "number":
        k = _number(tok, where)
        if at(i + 1) == ("op", "*"):
            kind2, col = at(i + 2)
            if kind2 != "name":
                raise DataError(f"{where}: expected a column after '{tok} *' in {text!r}")
            return col, sign * k, i + 3
        return None, sign * k, i + 1
    if kind == "name":
        op = at(i + 1)
        if op in (("op", "*"), ("op", "/")):
            kind2, num = at(i + 2)
            if kind2 != "number":
                raise DataError(
                    f"{where}: expected a number after '{tok} {op[1]}' in {text!r}; a derived channel is"
                    " a linear combination of columns (no product of two columns)"
                )
            k = _number(num, where)
            if op[1] == "/" and k == 0:
                raise DataError(f"{where}: division by zero in {text!r}")
            return tok, sign * (k if op[1] == "*" else 1.0 / k), i + 3
        return tok, sign, i + 1
    shown = "the end" if kind == "end" else repr(tok)
    raise DataError(f"{where}: expected a column or a number, found {shown} in {text!r}")


def parse_expression(text: str, where: str = "expression") -> Combination:
    """Read ``"Ph1 + Ph2"``, ``"1000 * P_kW"``, ``"T - 0.5"`` or ``"`a b` / 2"`` as a :class:`Combination`.

    Parameters
    ----------
    text : str
        The expression (see the module notes for the grammar).
    where : str
        Where it was written, for messages (``"column map house.toml: [columns].Ph.expr"``).

    Returns
    -------
    Combination

    Raises
    ------
    DataError
        For anything but a linear combination of columns and numbers, one line naming ``where``.
    """
    if not isinstance(text, str) or not text.strip():
        raise DataError(f'{where} must be a non-empty expression such as "Ph1 + Ph2", got {text!r}')
    if len(text) > MAX_EXPRESSION_LENGTH:
        raise DataError(f"{where}: the expression is longer than {MAX_EXPRESSION_LENGTH} characters")
    toks = _tokens(text, where)
    factors: dict[str, float] = {}
    offset, i, first = 0.0, 0, True
    while i < len(toks) or first:
        sign = 1.0
        if not first:
            kind, op = toks[i]
            if kind != "op" or op not in "+-":
                raise DataError(f"{where}: expected + or - before {op!r} in {text!r}")
            sign, i = (1.0 if op == "+" else -1.0), i + 1
        col, k, i = _term(toks, i, where, text)
        if col is None:
            offset += sign * k
        else:
            factors[col] = factors.get(col, 0.0) + sign * k
        if len(factors) > MAX_TERMS:
            raise DataError(f"{where}: more than {MAX_TERMS} columns in {text!r}")
        first = False
    if not factors:
        raise DataError(f"{where}: {text!r} names no column; a constant is written value = ...")
    return Combination(tuple(factors.items()), offset)
