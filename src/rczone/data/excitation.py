"""Are the inputs excited apart? Collinear inputs, named, with what would separate them.

Three heater powers that switch together (pairwise correlation 0.9998) drive the room as one
input: the data fix the sum of their effects and nothing else, and a fit puts one gain near its
upper bound and the others at 0 -- a verdict at a degenerate point that no widening of bounds
mends. Before any sensitivity, the inputs themselves show it (Belsley, Kuh & Welsch 1980, ch. 3):

* the **correlation matrix** ``R`` of the varying inputs (each centred and scaled);
* its **condition index** ``sqrt(lambda_max / lambda_min)``: the inputs are collinear when it is
  at least :data:`CONDITION_INDEX_COLLINEAR` (30, Belsley's "strong" dependence), and its
  numerical **rank** (eigenvalues above ``1e-10 lambda_max``);
* the **pairs** with ``|r| >=`` :data:`CORR_COLLINEAR` (0.95, the threshold at which
  :mod:`rczone.diagnostics.identifiability` calls two parameters confounded), grouped into sets of
  inputs that move together; without such a pair, the inputs whose variance inflation factor
  ``[R^{-1}]_jj`` is at least :data:`VIF_COLLINEAR` (10) name the dependence.

The advice says what separates them: a test that switches them apart (``rczone design`` with each
of them actuated), or one summed channel with one gain (a derived channel in the column map,
``expr = "Ph1 + Ph2 + Ph3"``).

References
----------
.. [1] D. A. Belsley, E. Kuh, R. E. Welsch, *Regression Diagnostics: Identifying Influential Data
   and Sources of Collinearity*, Wiley 1980, chapter 3 (condition indexes, variance inflation).
.. [2] E. Walter, L. Pronzato, *Identification of Parametric Models from Experimental Data*,
   Springer 1997, ch. 6 (inputs that do not excite the parameters apart).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

#: |correlation| of two inputs at or above which they are named as moving together.
CORR_COLLINEAR = 0.95
#: Condition index of the input correlation at or above which the inputs are collinear.
CONDITION_INDEX_COLLINEAR = 30.0
#: Variance inflation factor at or above which an input takes part in a dependence.
VIF_COLLINEAR = 10.0


@dataclass(frozen=True)
class Excitation:
    """How far apart the inputs are excited.

    Attributes
    ----------
    inputs : tuple of str
        The inputs analysed (those that vary over the data).
    constant : tuple of str
        Inputs constant over the data (they excite nothing).
    correlation : ndarray, shape (k, k)
    condition_index : float
        ``sqrt(lambda_max / lambda_min)`` of ``correlation`` (inf when singular).
    rank : int
        Numerical rank of ``correlation``.
    groups : tuple of tuple of str
        Sets of inputs that move together.
    pairs : tuple of (str, str, float)
        Pairs with ``|r| >= CORR_COLLINEAR`` and their correlation.
    """

    inputs: tuple[str, ...]
    constant: tuple[str, ...]
    correlation: np.ndarray
    condition_index: float
    rank: int
    groups: tuple[tuple[str, ...], ...]
    pairs: tuple[tuple[str, str, float], ...]

    @property
    def collinear(self) -> bool:
        """Whether some inputs are not excited apart."""
        return bool(self.groups)

    def finding(self, group: Sequence[str]) -> str:
        """One group in words: which inputs move together, how closely, and what would separate them."""
        inside = [abs(r) for a, b, r in self.pairs if a in group and b in group]
        how = (
            f"pairwise correlation {min(inside):.4g} or more"
            if inside
            else f"condition index {self.condition_index:.3g}"
        )
        names = ", ".join(group)
        return (
            f"the inputs {names} move together ({how}): the data fix only their combined effect, not each"
            f" one's; a test that switches them apart (rczone design, actuating {names} one at a time) or one"
            f' summed channel with one gain (a derived channel, expr = "{" + ".join(group)}") separates them'
        )

    def findings(self) -> list[str]:
        """Every group in words (empty when the inputs are excited apart)."""
        return [self.finding(g) for g in self.groups]

    def summary_lines(self) -> list[str]:
        """What ``diagnose``, ``fit`` and ``design`` print: the condition, then each collinear group."""
        from rich.markup import escape as esc

        if len(self.inputs) < 2:
            return []
        head = (
            f"input excitation: {len(self.inputs)} varying inputs, condition index {self.condition_index:.3g}"
            f" (collinear at {CONDITION_INDEX_COLLINEAR:g}), rank {self.rank}"
        )
        if not self.collinear:
            return [head + ": excited apart"]
        return [head, *(f"[yellow]collinear inputs:[/] {esc(f)}" for f in self.findings())]

    def to_dict(self) -> dict:
        """JSON-ready fields."""
        ci = self.condition_index
        return {
            "inputs": list(self.inputs),
            "constant": list(self.constant),
            "correlation": self.correlation.tolist(),
            "condition_index": ci if math.isfinite(ci) else None,
            "rank": self.rank,
            "collinear": [list(g) for g in self.groups],
            "pairs": [{"a": a, "b": b, "correlation": r} for a, b, r in self.pairs],
            "findings": self.findings(),
        }


def _groups(names: Sequence[str], pairs: Sequence[tuple[str, str, float]]) -> list[tuple[str, ...]]:
    """Connected sets of ``names`` joined by ``pairs``, in the order of ``names``."""
    parent = {n: n for n in names}

    def root(n: str) -> str:
        while parent[n] != n:
            n = parent[n]
        return n

    for a, b, _ in pairs:
        parent[root(a)] = root(b)
    sets: dict[str, list[str]] = {}
    for n in names:
        sets.setdefault(root(n), []).append(n)
    return [tuple(g) for g in sets.values() if len(g) > 1]


def input_excitation(u: np.ndarray, names: Sequence[str]) -> Excitation:
    """The excitation of the inputs ``u`` (module notes).

    Parameters
    ----------
    u : ndarray, shape (N, k)
        The inputs, time-first (NaN: missing, the sample skipped).
    names : sequence of str
        Their names.

    Returns
    -------
    Excitation
    """
    u = np.asarray(u, dtype=float).reshape(len(u), -1)
    names = tuple(names)
    ok = np.isfinite(u).all(axis=1)
    x = u[ok]
    sd = x.std(axis=0) if len(x) > 1 else np.zeros(u.shape[1])
    varying = sd > 1e-12 * np.maximum(1.0, np.abs(x).max(axis=0, initial=0.0))
    used = tuple(n for n, v in zip(names, varying, strict=True) if v)
    constant = tuple(n for n, v in zip(names, varying, strict=True) if not v)
    if len(used) < 2:
        return Excitation(used, constant, np.eye(len(used)), 1.0, len(used), (), ())
    z = (x[:, varying] - x[:, varying].mean(axis=0)) / sd[varying]
    corr = np.clip(z.T @ z / len(z), -1.0, 1.0)
    lam = np.linalg.eigvalsh(corr)
    top = float(lam[-1])
    rank = int(np.sum(lam > 1e-10 * top))
    ci = math.sqrt(top / lam[0]) if lam[0] > 1e-14 * top else math.inf
    pairs = tuple(
        (used[i], used[j], float(corr[i, j]))
        for i in range(len(used))
        for j in range(i + 1, len(used))
        if abs(corr[i, j]) >= CORR_COLLINEAR
    )
    groups = _groups(used, pairs)
    if not groups and ci >= CONDITION_INDEX_COLLINEAR:
        with np.errstate(all="ignore"):
            vif = np.diag(np.linalg.pinv(corr))
        inflated = tuple(n for n, v in zip(used, vif, strict=True) if v >= VIF_COLLINEAR)
        groups = [inflated] if len(inflated) > 1 else []
    return Excitation(used, constant, corr, ci, rank, tuple(groups), pairs)
