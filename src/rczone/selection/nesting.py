"""Is one RC model a special case of another? Nesting detected from the two networks' structure.

A likelihood-ratio test compares two models only when one is *nested* in the other: every
input-output behaviour of the simpler model is one of the richer model's, obtained by holding
some of the richer model's parameters at special values. rczone detects this from the networks;
it is never assumed from names or parameter counts.

The rule
--------
The richer network ``B`` is *restricted* by setting some of its free parameters to a limit of
their domain, each an exact statement about the network:

==================  =====================================================================
restriction         what it does to the network
==================  =====================================================================
capacity ``C -> 0``  its node becomes massless (an algebraic node, eliminated exactly)
``R -> 0``           the resistor's two ends merge into one node (capacities and heat inputs
                     add; merged with a boundary, the node is held at the boundary)
``R -> inf``         the resistor is removed
gain ``g = 0``       the heat input no longer reaches that node (only where ``g = 0`` is in the
                     declared bounds, e.g. a solar aperture ``Aw``)
magnitude ``-> 0``   a disturbance (:mod:`rczone.network.disturbance`) no longer reaches any node:
                     its latent states are invisible and it is removed with its hyper-parameters
==================  =====================================================================

A disturbance of ``A`` must be one of ``B``'s, declared identically (same name, kind, gains and
hyper-parameters); ``B``'s other disturbances are restricted by a zero magnitude.

The restricted network is then reduced by exact eliminations, repeated until none applies: a
massless node joined by one resistor passes its heat inputs to the neighbour and disappears; a
massless node between two resistors and without heat inputs becomes one resistor (the sum of the
two); parallel resistors become one; a part of the network joined to no output by resistors (it
cannot be seen) is removed; inputs that no longer act are dropped.

``A`` is nested in ``B`` when some restriction of ``B`` reduces to ``A``'s own reduced network up
to the names of unmeasured nodes (outputs, inputs and their units must be the same), with
every element value of ``A`` *realizable*: the matching element of the reduced ``B`` is a sum or
parallel combination of free parameters of ``B`` that appear in no other element (so it takes
any positive value), or the same constant; elements of ``A`` that share a parameter match
identical elements of ``B``. The free noise levels of ``A`` must have free counterparts in ``B``
on the matched states. Search boxes are not part of a model and are ignored.

The rule is *sound* rather than complete: when it says nested, the restricted ``B`` reproduces
``A`` exactly (the tests check this by simulating both); it can miss a nesting that needs a
transformation it does not know (a star-mesh transform of a massless node with three or more
resistors, parameters that enter through ties). Networks with tied parameters are not analysed.

Degrees of freedom and boundaries
---------------------------------
The likelihood-ratio statistic ``2 (log L_B - log L_A)`` is referred to ``chi2(d)`` with ``d``
the difference in the number of free parameters, as Bacher & Madsen (2011) do. Every restriction
but an interior gain puts a parameter on the boundary of its domain, where the statistic is
asymptotically a mixture of chi-squares (chi-bar-squared) that is stochastically *smaller* than
``chi2(d)`` (Self & Liang 1987): ``chi2(d)`` is the conservative choice and the one used to
decide. The mixture for independent boundary restrictions, ``sum_i C(s, i) 2^-s chi2(d - s + i)``
with ``s`` of them, is reported beside it. Where a restriction leaves parameters without effect
(the split of ``Rie + Rea`` when ``Ce -> 0``), those are unidentified under the simpler model and
the asymptotic theory holds only approximately (Davies 1987); the p-values are then a guide.
A disturbance removed by its magnitude is such a case: its magnitude sits on the boundary (one of
the ``s`` restrictions) and its length scale (and period) are unidentified under ``A``; the
chi-bar-squared p-value treats them as fixed at their estimates, so it is a lower bound, and the
decision uses ``chi2(d)``, conservative for the boundary but not guaranteed so for the unidentified
length scale (Davies 1987): a p-value near the level is not evidence either way.

References
----------
.. [1] P. Bacher, H. Madsen, "Identifying suitable models for the heat dynamics of buildings",
   Energy and Buildings 43 (2011) 1511-1522, section 4 (forward selection by likelihood-ratio tests).
.. [2] S. G. Self, K.-Y. Liang, "Asymptotic properties of maximum likelihood estimators and
   likelihood ratio tests under nonstandard conditions", J. Am. Stat. Assoc. 82 (1987) 605-610.
.. [3] R. B. Davies, "Hypothesis testing when a nuisance parameter is present only under the
   alternative", Biometrika 74 (1987) 33-43.
.. [4] F. Doerfler, F. Bullo, "Kron reduction of graphs with applications to electrical
   networks", IEEE Trans. Circuits Syst. I 60 (2013) 150-163 (elimination of massless nodes).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from rczone.network import RCNetwork
from rczone.network.stochastic import MEASUREMENT_NOISE, is_reserved, parameter_name, parse_name

#: Most unmeasured nodes whose correspondence is searched (their permutations are tried).
MAX_MATCHED_NODES = 7
#: Most restrictions tried together.
MAX_RESTRICTIONS = 6

# A term is an element value as an expression of one network's free parameters:
# ("p", name) a free parameter, ("c", value) a constant, ("+", terms) a sum, ("||", terms) a
# parallel combination (of resistances). Terms are tuples, so they compare and sort.
Term = tuple

_SYMBOL = {"0": "0", "inf": "∞"}


class _Invalid(Exception):
    """A restriction that makes the network meaningless (two boundaries shorted, an output lost)."""


def _sum(terms: Iterable[Term]) -> Term:
    flat: list[Term] = []
    const = 0.0
    for t in terms:
        for s in t[1] if t[0] == "+" else (t,):
            if s[0] == "c":
                const += s[1]
            else:
                flat.append(s)
    if const != 0.0 or not flat:
        flat.append(("c", const))
    return flat[0] if len(flat) == 1 else ("+", tuple(sorted(flat)))


def _parallel(terms: Iterable[Term]) -> Term:
    flat: list[Term] = []
    inv = 0.0
    for t in terms:
        for s in t[1] if t[0] == "||" else (t,):
            if s[0] == "c":
                inv += 1.0 / s[1]
            else:
                flat.append(s)
    if inv:
        flat.append(("c", 1.0 / inv))
    return flat[0] if len(flat) == 1 else ("||", tuple(sorted(flat)))


def _params(t: Term) -> frozenset[str]:
    if t[0] == "p":
        return frozenset((t[1],))
    if t[0] == "c":
        return frozenset()
    return frozenset().union(*(_params(s) for s in t[1]))


def _has_constant(t: Term) -> bool:
    return t[0] == "c" or (t[0] in ("+", "||") and any(_has_constant(s) for s in t[1]))


def _text(t: Term) -> str:
    if t[0] == "p":
        return t[1]
    if t[0] == "c":
        return f"{t[1]:g}"
    return "(" + (" + " if t[0] == "+" else " || ").join(_text(s) for s in t[1]) + ")"


@dataclass
class _Skeleton:
    """A network as mutable element lists, for restriction and reduction (private, rebuilt per use)."""

    nodes: dict[str, Term | None]
    order: list[str]
    resistors: list[tuple[str, str, Term]]
    heat: dict[str, dict[str, Term]]
    units: dict[str, str]
    supply: list[tuple[str, str, str, Term]]
    boundaries: set[str]
    outputs: tuple[str, ...]

    @classmethod
    def of(cls, net: RCNetwork, free: set[str], values: Mapping[str, float]) -> _Skeleton:
        def term(v: object) -> Term:
            if isinstance(v, str):
                return ("p", v) if v in free else ("c", float(values[v]))
            return ("c", float(v))

        return cls(
            nodes={n.name: None if n.capacity is None else term(n.capacity) for n in net.nodes},
            order=[n.name for n in net.nodes],
            resistors=[(r.a, r.b, term(r.resistance)) for r in net.resistors],
            heat={h.name: {node: term(g) for node, g in h.split} for h in net.heat_inputs},
            units={h.name: h.unit for h in net.heat_inputs},
            supply=[(s.node, s.flow, s.temperature, term(s.cp)) for s in net.supply_air],
            boundaries=set(net.boundaries),
            outputs=tuple(net.outputs),
        )

    # ------------------------------------------------------------------ restrictions
    def restrict(self, moves: Sequence[tuple[str, str]]) -> None:
        merges = []
        for name, to in moves:
            p = ("p", name)
            for n, c in self.nodes.items():
                if c == p:
                    self.nodes[n] = None
            if to == "inf":
                self.resistors = [r for r in self.resistors if r[2] != p]
            elif to == "0":
                merges += [(a, b) for a, b, r in self.resistors if r == p]
                for split in self.heat.values():
                    for node in [k for k, g in split.items() if g == p]:
                        del split[node]
        self._contract(merges)

    def _contract(self, pairs: list[tuple[str, str]]) -> None:
        if not pairs:
            return
        parent: dict[str, str] = {}

        def find(x: str) -> str:
            while parent.get(x, x) != x:
                x = parent[x]
            return x

        for a, b in pairs:
            parent[find(a)] = find(b)
        groups: dict[str, list[str]] = {}
        for x in {x for pair in pairs for x in pair}:
            groups.setdefault(find(x), []).append(x)
        rename: dict[str, str] = {}
        for members in groups.values():
            bounds = [m for m in members if m in self.boundaries]
            nodes = sorted((m for m in members if m in self.nodes), key=self.order.index)
            outs = [m for m in nodes if m in self.outputs]
            if len(bounds) > 1 or (bounds and outs) or len(outs) > 1:
                raise _Invalid
            if bounds:
                for m in nodes:  # held at the boundary: its state and what acts on it are gone
                    del self.nodes[m]
                    for split in self.heat.values():
                        split.pop(m, None)
                    self.supply = [s for s in self.supply if s[0] != m]
                    rename[m] = bounds[0]
                continue
            keep = outs[0] if outs else nodes[0]
            caps = [self.nodes[m] for m in nodes if self.nodes[m] is not None]
            self.nodes[keep] = _sum(caps) if caps else None
            for split in self.heat.values():
                gains = [split.pop(m) for m in nodes if m in split]
                if gains:
                    split[keep] = _sum(gains)
            for m in nodes:
                if m != keep:
                    del self.nodes[m]
                    rename[m] = keep
        self.resistors = [(rename.get(a, a), rename.get(b, b), r) for a, b, r in self.resistors]
        self.supply = [(rename.get(n, n), f, t, cp) for n, f, t, cp in self.supply]

    # ------------------------------------------------------------------ reduction
    def reduce(self) -> None:
        """Apply the exact eliminations until none applies (see the module notes)."""
        changed = True
        while changed:
            changed = self._tidy()
            for n in list(self.nodes):
                if self.nodes[n] is None and n not in self.outputs and self._eliminate(n):
                    changed = True
                    break

    def _tidy(self) -> bool:
        before = (len(self.resistors), len(self.nodes), sum(map(len, self.heat.values())))
        res = [
            (a, b, r)
            for a, b, r in self.resistors
            if a != b and not (a in self.boundaries and b in self.boundaries)
        ]
        merged: dict[tuple[str, str], list[Term]] = {}
        for a, b, r in res:
            merged.setdefault(tuple(sorted((a, b))), []).append(r)
        self.resistors = [(a, b, _parallel(rs)) for (a, b), rs in merged.items()]
        # parts joined to no output by resistors between nodes cannot be seen
        seen, todo = set(), [o for o in self.outputs if o in self.nodes]
        while todo:
            x = todo.pop()
            if x in seen:
                continue
            seen.add(x)
            todo += [
                b if a == x else a
                for a, b, _ in self.resistors
                if x in (a, b) and (b if a == x else a) in self.nodes
            ]
        for n in [n for n in self.nodes if n not in seen]:
            del self.nodes[n]
        self.resistors = [(a, b, r) for a, b, r in self.resistors if (a in seen or b in seen)]
        self.supply = [s for s in self.supply if s[0] in seen]
        for name in list(self.heat):
            self.heat[name] = {k: g for k, g in self.heat[name].items() if k in seen}
            if not self.heat[name]:
                del self.heat[name]
        return before != (len(self.resistors), len(self.nodes), sum(map(len, self.heat.values())))

    def _eliminate(self, n: str) -> bool:
        """Eliminate the massless node ``n`` where an exact rule applies; False where none does."""
        if any(s[0] == n for s in self.supply):
            return False
        mine = [r for r in self.resistors if n in r[:2]]
        heated = [name for name, split in self.heat.items() if n in split]
        if not mine:
            if heated:
                raise _Invalid  # heat into a node with no way out
            del self.nodes[n]
            return True
        if len(mine) == 1:
            a, b, _ = mine[0]
            other = b if a == n else a
            for name in heated:
                g = self.heat[name].pop(n)
                if other in self.nodes:
                    old = self.heat[name].get(other)
                    self.heat[name][other] = g if old is None else _sum((old, g))
            self.resistors.remove(mine[0])
            del self.nodes[n]
            return True
        if len(mine) == 2 and not heated:
            (a1, b1, r1), (a2, b2, r2) = mine
            x, y = (b1 if a1 == n else a1), (b2 if a2 == n else a2)
            self.resistors = [r for r in self.resistors if r not in mine]
            self.resistors.append((x, y, _sum((r1, r2))))
            del self.nodes[n]
            return True
        return False

    def inputs(self) -> frozenset[tuple[str, ...]]:
        """The signals the reduced network reads: temperatures, flows, heat inputs with their units."""
        temps = {x for a, b, _ in self.resistors for x in (a, b) if x in self.boundaries}
        temps |= {s[2] for s in self.supply}
        return frozenset(
            {("T", t) for t in temps}
            | {("m", s[1]) for s in self.supply}
            | {("Q", h, self.units[h]) for h in self.heat}
        )


@dataclass(frozen=True)
class Nesting:
    """How the simpler model is a special case of the richer one.

    Attributes
    ----------
    simple, rich : str
        Names of the two models.
    restriction : tuple of (str, str)
        ``(parameter, "0" | "inf")`` of the richer model.
    correspondence : tuple of (str, str)
        Each element value of the simpler model beside the expression of the richer model's
        parameters that takes its place (``"Ria" <- "(Rea + Rie)"``).
    node_map : dict of str to str
        Node of the simpler model to node of the restricted richer one.
    df : int
        Difference in the number of free parameters (the test's degrees of freedom).
    n_boundary : int
        Restrictions at a boundary of the parameter's domain.
    kinds : tuple of str
        Kind of each restricted parameter (``"resistance"``, ``"capacitance"``, ``"gain"``).
    terms : tuple of (Term, Term)
        The correspondence as terms, for :func:`realize`.
    """

    simple: str
    rich: str
    restriction: tuple[tuple[str, str], ...]
    correspondence: tuple[tuple[str, str], ...]
    node_map: Mapping[str, str]
    df: int
    n_boundary: int
    kinds: tuple[str, ...] = ()
    terms: tuple[tuple[Term, Term], ...] = field(repr=False, default=())

    def describe(self) -> str:
        """``"Ce -> 0"``, ``"Rih -> 0, Aw = 0"``... (``"none"`` when no restriction is needed)."""
        if not self.restriction:
            return "none"
        return ", ".join(
            f"{p} = 0" if kind == "gain" else f"{p} -> {_SYMBOL[to]}"
            for (p, to), kind in zip(self.restriction, self.kinds)
        )

    def to_dict(self) -> dict:
        return {
            "simple": self.simple,
            "rich": self.rich,
            "restriction": self.describe(),
            "correspondence": {a: b for a, b in self.correspondence},
            "df": self.df,
        }


def _moves(net: RCNetwork, free: set[str]) -> list[list[tuple[str, str]]]:
    """The possible restrictions of each free parameter (a list of alternatives per parameter)."""
    use: dict[str, set[str]] = {}
    for n in net.nodes:
        if isinstance(n.capacity, str):
            use.setdefault(n.capacity, set()).add("capacity")
    for r in net.resistors:
        if isinstance(r.resistance, str):
            use.setdefault(r.resistance, set()).add("resistance")
    for h in net.heat_inputs:
        for _, g in h.split:
            if isinstance(g, str):
                use.setdefault(g, set()).add("gain")
    for s in net.supply_air:
        if isinstance(s.cp, str):
            use.setdefault(s.cp, set()).add("cp")
    out = []
    for name, where in use.items():
        if name not in free or len(where) != 1:
            continue
        (slot,) = where
        if slot == "capacity":
            out.append([(name, "0")])
        elif slot == "resistance":
            out.append([(name, "0"), (name, "inf")])
        elif slot == "gain":
            b = net.parameters[name].bounds
            if b is None or b[0] <= 0.0 <= b[1]:
                out.append([(name, "0")])
    return out


def _realizable(pairs: list[tuple[Term, Term]]) -> bool:
    """Whether every element of the simpler model can be reproduced (see the module notes)."""
    by_a: dict[str, tuple[Term, Term]] = {}
    by_b: dict[str, tuple[Term, Term]] = {}
    for a, b in pairs:
        pa, pb = _params(a), _params(b)
        if pb and _has_constant(b):
            return False  # partly fixed: its range is not the whole domain (conservative)
        if pa and not pb:
            return False  # a free value of the simpler model against a fixed one
        if not pa and not pb and not math.isclose(a[1], b[1], rel_tol=1e-9):
            return False
        for p in pa:
            if by_a.setdefault(p, (a, b)) != (a, b):
                return False
        for p in pb:
            if by_b.setdefault(p, (a, b)) != (a, b):
                return False
    return True


def _match(a: _Skeleton, b: _Skeleton) -> tuple[dict[str, str], list[tuple[Term, Term]]] | None:
    """A node correspondence under which ``b`` has ``a``'s elements, and the element pairs."""
    if a.outputs != b.outputs or a.inputs() != b.inputs() or len(a.nodes) != len(b.nodes):
        return None
    inner_a = [n for n in a.nodes if n not in a.outputs]
    inner_b = [n for n in b.nodes if n not in b.outputs]
    if len(inner_a) > MAX_MATCHED_NODES:
        return None
    for perm in itertools.permutations(inner_b):
        phi = {**{o: o for o in a.outputs}, **dict(zip(inner_a, perm))}
        pairs = _pairs(a, b, phi)
        if pairs is not None and _realizable(pairs):
            return phi, pairs
    return None


def _pairs(a: _Skeleton, b: _Skeleton, phi: dict[str, str]) -> list[tuple[Term, Term]] | None:
    def m(x: str) -> str:
        return phi.get(x, x)

    pairs: list[tuple[Term, Term]] = []
    for n, c in a.nodes.items():
        cb = b.nodes[phi[n]]
        if (c is None) != (cb is None):
            return None
        if c is not None:
            pairs.append((c, cb))
    rb = {frozenset((x, y)): r for x, y, r in b.resistors}
    if len(rb) != len(a.resistors):
        return None
    for x, y, r in a.resistors:
        key = frozenset((m(x), m(y)))
        if key not in rb:
            return None
        pairs.append((r, rb[key]))
    for name, split in a.heat.items():
        sb = b.heat[name]
        if {m(k) for k in split} != set(sb):
            return None
        pairs += [(g, sb[m(k)]) for k, g in split.items()]
    sup_b = {(n, f, t): cp for n, f, t, cp in b.supply}
    if len(sup_b) != len(a.supply):
        return None
    for n, f, t, cp in a.supply:
        if (m(n), f, t) not in sup_b:
            return None
        pairs.append((cp, sup_b[(m(n), f, t)]))
    return pairs


def _noise_matches(free_a: set[str], free_b: set[str], phi: Mapping[str, str]) -> bool:
    for name in free_a:
        p = parse_name(name)
        if p is not None and p.kind != MEASUREMENT_NOISE:
            name = parameter_name(p.kind, phi.get(p.target, p.target))
        if is_reserved(name) and name not in free_b:
            return False
    return True


def nesting(
    simple: RCNetwork,
    rich: RCNetwork,
    free_simple: Sequence[str] | None = None,
    free_rich: Sequence[str] | None = None,
    values_simple: Mapping[str, float] | None = None,
    values_rich: Mapping[str, float] | None = None,
) -> Nesting | None:
    """How ``simple`` is nested in ``rich``, or None when the rule finds no nesting.

    Parameters
    ----------
    simple, rich : RCNetwork
    free_simple, free_rich : sequence of str, optional
        The free parameters of each fit (network parameters and noise levels); default each
        network's :attr:`~rczone.network.RCNetwork.default_free`. Non-free parameters are
        constants at their value.
    values_simple, values_rich : mapping, optional
        Values of the non-free parameters; default the declared ones.

    Returns
    -------
    Nesting or None
        The first restriction found with the fewest restricted parameters.
    """
    free_a = set(free_simple if free_simple is not None else simple.default_free)
    free_b = set(free_rich if free_rich is not None else rich.default_free)
    df = len(free_b) - len(free_a)
    if df < 1:
        return None
    if any(p.is_tied for net in (simple, rich) for p in net.parameters.values()):
        return None
    removed = _removed_disturbances(simple, rich, free_b)
    if removed is None:
        return None
    gone = {v for d in removed for _, v in (*d.hyperparameters, *d.gains) if isinstance(v, str)}
    if gone & ({*free_a} | _element_parameters(rich)):
        return None  # a removed disturbance's parameter is used elsewhere: not a clean removal
    gone &= free_b
    free_b = free_b - gone
    removal = tuple((d.magnitude, "0") for d in removed)
    va = {**simple.values(), **dict(values_simple or {})}
    vb = {**rich.values(), **dict(values_rich or {})}
    a = _Skeleton.of(simple, free_a, va)
    try:
        a.reduce()
    except _Invalid:  # pragma: no cover - a valid network reduces
        return None
    options = _moves(rich, free_b)
    for size in range(0, min(len(options), df - len(gone), MAX_RESTRICTIONS) + 1):
        for chosen in itertools.combinations(options, size):
            for moves in itertools.product(*chosen):
                b = _Skeleton.of(rich, free_b, vb)
                try:
                    b.restrict(moves)
                    b.reduce()
                except _Invalid:
                    continue
                found = _match(a, b)
                if found is None or not _noise_matches(free_a, free_b, found[0]):
                    continue
                phi, pairs = found
                kinds = tuple(rich.parameters[p].kind for p, _ in moves) + ("magnitude",) * len(removal)
                return Nesting(
                    simple.name,
                    rich.name,
                    tuple(moves) + removal,
                    tuple((_text(x), _text(y)) for x, y in pairs if _params(x) or _params(y)),
                    phi,
                    df,
                    sum(_at_boundary(rich, p, k) for (p, _), k in zip(moves, kinds)) + len(removal),
                    kinds,
                    tuple(pairs),
                )
    return None


def _removed_disturbances(simple: RCNetwork, rich: RCNetwork, free_b: set[str]) -> list | None:
    """``rich``'s disturbances that ``simple`` lacks, each removable by a free magnitude; None if none fits."""
    mine = set(simple.disturbances)
    if not mine <= set(rich.disturbances):
        return None  # a disturbance of the simpler model must be the richer model's, declared identically
    removed = [d for d in rich.disturbances if d not in mine]
    if any(not isinstance(d.magnitude, str) or d.magnitude not in free_b for d in removed):
        return None
    return removed


def _element_parameters(net: RCNetwork) -> set[str]:
    """Parameter names the network's thermal elements use (nodes, resistors, heat inputs, supply air)."""
    used = {n.capacity for n in net.nodes} | {r.resistance for r in net.resistors}
    used |= {g for h in net.heat_inputs for _, g in h.split} | {s.cp for s in net.supply_air}
    return {v for v in used if isinstance(v, str)}


def _at_boundary(net: RCNetwork, name: str, kind: str) -> bool:
    """A capacity or resistance at 0 or infinity is on the boundary; a gain at 0 only at a bound."""
    b = net.parameters[name].bounds
    return kind != "gain" or (b is not None and b[0] == 0.0)


def realize(
    nest: Nesting, simple_values: Mapping[str, float], rich_values: Mapping[str, float], eps: float = 1e-6
) -> dict[str, float]:
    """Values of the richer model's parameters that reproduce the simpler model (up to ``eps``).

    Each element of the simpler model is given to the matching expression of the richer one
    (a sum split equally, a parallel combination each ``k`` times the value); a restricted
    capacity or resistance goes to ``eps`` (``0``) or ``1 / eps`` (``inf``) times its value in
    ``rich_values``, a restricted gain to 0. Other parameters keep their ``rich_values``.
    """
    out = dict(rich_values)

    def give(t: Term, v: float) -> None:
        if t[0] == "p":
            out[t[1]] = v
        elif t[0] == "+":
            for s in t[1]:
                give(s, v / len(t[1]))
        elif t[0] == "||":
            for s in t[1]:
                give(s, v * len(t[1]))

    def value(t: Term) -> float:
        if t[0] == "p":
            return float(simple_values[t[1]])
        if t[0] == "c":
            return t[1]
        vals = [value(s) for s in t[1]]
        return sum(vals) if t[0] == "+" else 1.0 / sum(1.0 / v for v in vals)

    for a, b in nest.terms:
        if _params(b):
            give(b, value(a))
    for (p, to), kind in zip(nest.restriction, nest.kinds):
        out[p] = 0.0 if kind == "gain" else rich_values[p] * (eps if to == "0" else 1.0 / eps)
    # a removed disturbance's magnitude is at eps times its value: the simpler model to O(eps^2)
    return out
