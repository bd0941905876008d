"""Named physical parameters of an RC network, tied parameters and their resolution.

A parameter is either *base* (a value the user or an optimizer supplies) or *tied*
(an arithmetic expression over other parameters, such as the paper's ``R1 = Rw/2``).
:func:`resolve` turns a mapping of base values into the value of every parameter,
checking names, signs and expressions on the way. It never mutates its inputs.

A base parameter also carries its estimation settings, as lmfit's and pySIP's parameters do:
``bounds`` (the box an optimizer searches, physical units) and ``fixed`` (held at its value
unless a fit names it explicitly). The structure stays frozen; a fit never changes it.

Expressions are untrusted text (they come from model files): they are parsed into a small
tree of numbers, names and ``+ - * / **`` and evaluated in floating point by rczone itself,
never by Python's ``eval``. Length, size, nesting and constant exponents are bounded, and a
result that overflows, is not a real number or is not finite is an error, so an expression
can neither run code nor hang nor crash the process.
"""

from __future__ import annotations

import ast
import cmath
import functools
import keyword
import math
import operator
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from rczone.errors import ParameterError, did_you_mean
from rczone.network.prior import Prior
from rczone.network.stochastic import RESERVED_PREFIXES, is_reserved

#: Kinds of parameter; those in :data:`POSITIVE_KINDS` must be strictly positive. ``magnitude`` (W)
#: and ``time`` (s) are the hyper-parameters of a disturbance (:mod:`rczone.network.disturbance`).
KINDS = ("resistance", "capacitance", "gain", "magnitude", "time", "other")

#: Kinds estimated by default (unless declared ``fixed``).
ESTIMATED_KINDS = ("resistance", "capacitance", "gain", "magnitude", "time")

#: Kinds whose values are strictly positive (estimated in log space; may have a log-normal prior).
POSITIVE_KINDS = ("resistance", "capacitance", "magnitude", "time")

_UNITS = {"resistance": "K/W", "capacitance": "J/K", "gain": "1", "magnitude": "W", "time": "s", "other": ""}

_BINOPS = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
}
_UNOPS = {ast.USub: operator.neg, ast.UAdd: operator.pos}

#: Limits on a tie expression: characters, tree nodes, nesting depth, |constant exponent|.
MAX_EXPRESSION_LENGTH = 200
MAX_EXPRESSION_NODES = 64
MAX_EXPRESSION_DEPTH = 16
MAX_CONSTANT_EXPONENT = 64.0


@dataclass(frozen=True)
class Parameter:
    """One named parameter of a network.

    Parameters
    ----------
    name : str
        Identifier used by the network elements and in ``theta`` mappings.
    kind : {"resistance", "capacitance", "gain", "magnitude", "time", "other"}
        Physical role; resistances, capacitances, magnitudes and times must be > 0.
    value : float, optional
        Default (construction) value in SI units, used when ``theta`` omits it.
    expr : str, optional
        Arithmetic expression over other parameters (``"Rw/2"``). A tied parameter
        cannot also be given in ``theta``.
    unit : str, optional
        SI unit, defaults from ``kind`` (K/W, J/K, 1).
    description : str
        Free text for reports.
    bounds : (float, float), optional
        Box an estimation searches, physical units; ``lower < value < upper`` and, for a
        resistance or capacitance, ``lower > 0``. Default: chosen by the estimation
        (a factor 1000 around the value for a positive parameter).
    fixed : bool
        Held at ``value`` unless a fit names it as free. Default False: base resistances,
        capacitances and gains are estimated (:attr:`RCNetwork.default_free`).
    prior : Prior, optional
        Prior distribution of the value (:mod:`rczone.network.prior`); a log-normal only for a
        resistance or a capacitance. Declared and kept, not yet used by an estimator.
    """

    name: str
    kind: str = "other"
    value: float | None = None
    expr: str | None = None
    unit: str | None = None
    description: str = ""
    bounds: tuple[float, float] | None = None
    fixed: bool = False
    prior: Prior | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.isidentifier() or keyword.iskeyword(self.name):
            raise ParameterError(f"parameter name {self.name!r} is not a valid identifier")
        if is_reserved(self.name):
            raise ParameterError(
                f"parameter name {self.name!r}: names starting with {' or '.join(RESERVED_PREFIXES)} are"
                " reserved for the noise and initial-state parameters of the estimation"
            )
        if self.kind not in KINDS:
            raise ParameterError(
                f"parameter {self.name!r}: kind {self.kind!r} is not one of {', '.join(KINDS)}"
            )
        if self.unit is None:
            object.__setattr__(self, "unit", _UNITS[self.kind])
        if self.expr is not None:
            if self.value is not None:
                raise ParameterError(f"parameter {self.name!r} has both a value and an expression; give one")
            expression_names(self.expr)  # syntax check now, not at first use
        if self.value is not None:
            try:
                if isinstance(self.value, bool):
                    raise TypeError
                object.__setattr__(self, "value", float(self.value))
            except (TypeError, ValueError, OverflowError):
                raise ParameterError(
                    f"parameter {self.name!r}: value {self.value!r} is not a number"
                ) from None
            _check_value(self, self.value)
        if not isinstance(self.fixed, bool):
            raise ParameterError(f"parameter {self.name!r}: fixed must be true or false, got {self.fixed!r}")
        if self.expr is not None and (self.bounds is not None or self.fixed):
            raise ParameterError(
                f"parameter {self.name!r} is tied ({self.name} = {self.expr}); it follows its expression,"
                " so bounds and fixed belong to the parameters it depends on"
            )
        if self.bounds is not None:
            object.__setattr__(self, "bounds", _check_bounds(self, self.bounds))
        if self.prior is not None:
            _check_prior(self, self.prior)

    @property
    def is_tied(self) -> bool:
        """True when the parameter is defined by an expression."""
        return self.expr is not None


def _check_prior(p: Parameter, prior: object) -> None:
    if not isinstance(prior, Prior):
        raise ParameterError(
            f"parameter {p.name!r}: prior must be a Prior, got {type(prior).__name__}"
            " (e.g. Prior('lognormal', median=0.01, sigma=0.7))"
        )
    if p.is_tied:
        raise ParameterError(
            f"parameter {p.name!r} is tied ({p.name} = {p.expr}); it follows its expression,"
            " so a prior belongs to the parameters it depends on"
        )
    if prior.needs_positive and p.kind not in POSITIVE_KINDS:
        raise ParameterError(
            f"parameter {p.name!r}: a {prior.dist} prior needs a positive parameter (a resistance, a"
            f" capacitance, a magnitude or a time), not a {p.kind}; use a normal or uniform prior"
        )


def _check_bounds(p: Parameter, bounds: object) -> tuple[float, float]:
    try:
        lo, hi = (float(b) for b in bounds)  # type: ignore[union-attr]
    except (TypeError, ValueError):
        raise ParameterError(
            f"parameter {p.name!r}: bounds must be two numbers [lower, upper], got {bounds!r}"
        ) from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ParameterError(
            f"parameter {p.name!r}: bounds [{lo:g}, {hi:g}] must be finite with lower < upper"
            " (they are never swapped)"
        )
    if p.kind in POSITIVE_KINDS and lo <= 0:
        raise ParameterError(
            f"parameter {p.name!r}: the lower bound of a {p.kind} must be > 0, got {lo:g}"
            " (it is estimated in log space)"
        )
    if p.value is not None and not lo < p.value < hi:
        raise ParameterError(
            f"parameter {p.name!r} = {p.value:g} {p.unit} is not strictly inside its bounds"
            f" [{lo:g}, {hi:g}]; move the value or widen the bounds"
        )
    return lo, hi


def _check_value(p: Parameter, v: float) -> None:
    if not math.isfinite(v):
        raise ParameterError(f"parameter {p.name!r} = {v!r} is not finite")
    if p.kind in POSITIVE_KINDS and v <= 0.0:
        raise ParameterError(
            f"parameter {p.name!r} = {v:g} {p.unit}: a {p.kind} must be > 0"
            " (use a very small or very large value to approximate a short or an open)"
        )


def _parse(expr: str) -> ast.expr:
    """The syntax tree of a tie expression, within the size limits, or :class:`ParameterError`."""
    if not isinstance(expr, str):
        raise ParameterError(f"a parameter expression must be text, got {type(expr).__name__}")
    if len(expr) > MAX_EXPRESSION_LENGTH:
        raise ParameterError(
            f"parameter expression of {len(expr)} characters is longer than the limit of"
            f" {MAX_EXPRESSION_LENGTH}; write ties as short arithmetic such as 'Rw/2'"
        )
    try:
        tree = ast.parse(expr, mode="eval")
    except SyntaxError as exc:
        raise ParameterError(f"invalid parameter expression {expr!r}: {exc.msg}") from None
    except (RecursionError, MemoryError, ValueError):
        raise ParameterError(f"invalid parameter expression {expr!r}: too deeply nested") from None
    return tree.body


def _check_tree(expr: str, node: ast.AST, depth: int, count: list[int]) -> None:
    count[0] += 1
    if count[0] > MAX_EXPRESSION_NODES:
        raise ParameterError(
            f"parameter expression {expr!r} has more than {MAX_EXPRESSION_NODES} terms; write ties"
            " as short arithmetic"
        )
    if depth > MAX_EXPRESSION_DEPTH:
        raise ParameterError(
            f"parameter expression {expr!r} is nested more than {MAX_EXPRESSION_DEPTH} levels deep"
        )
    if isinstance(node, ast.Name):
        return
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise ParameterError(f"parameter expression {expr!r} contains a non-number")
        if isinstance(node.value, float) and not math.isfinite(node.value):
            raise ParameterError(f"parameter expression {expr!r} contains a non-finite number")
        return
    if isinstance(node, ast.UnaryOp) and type(node.op) in _UNOPS:
        _check_tree(expr, node.operand, depth + 1, count)
        return
    if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
        if isinstance(node.op, ast.Pow):
            k = _constant(node.right)
            if k is not None and not abs(k) <= MAX_CONSTANT_EXPONENT:
                raise ParameterError(
                    f"parameter expression {expr!r}: exponent {k:g} is larger than"
                    f" {MAX_CONSTANT_EXPONENT:g} in magnitude"
                )
        _check_tree(expr, node.left, depth + 1, count)
        _check_tree(expr, node.right, depth + 1, count)
        return
    raise ParameterError(
        f"parameter expression {expr!r} uses {type(node).__name__}; only numbers,"
        " parameter names, + - * / ** and parentheses are allowed"
    )


def _constant(node: ast.AST) -> float | None:
    """The value of a signed numeric literal, else None."""
    sign = 1.0
    while isinstance(node, ast.UnaryOp) and type(node.op) in _UNOPS:
        sign = -sign if isinstance(node.op, ast.USub) else sign
        node = node.operand
    if (
        isinstance(node, ast.Constant)
        and isinstance(node.value, (int, float))
        and not isinstance(node.value, bool)
    ):
        try:
            return sign * float(node.value)
        except OverflowError:
            return math.inf
    return None


def expression_names(expr: str) -> tuple[str, ...]:
    """Names used in a parameter expression, validating its syntax and size.

    Only numbers, names, ``+ - * / **`` and parentheses are allowed, within
    :data:`MAX_EXPRESSION_LENGTH` characters, :data:`MAX_EXPRESSION_NODES` nodes,
    :data:`MAX_EXPRESSION_DEPTH` levels and constant exponents up to
    :data:`MAX_CONSTANT_EXPONENT` in magnitude.
    """
    return _program(expr)[1]


Number = float | complex


def _real_pow(a: Number, b: Number) -> Number:
    v = a**b
    if isinstance(v, complex) and not (isinstance(a, complex) or isinstance(b, complex)):
        raise ArithmeticError("is not a real number (a negative number to a fractional power)")
    return v


def _closure(node: ast.AST) -> Callable[[Mapping[str, Number]], Number]:
    """A function of the parameter values that evaluates ``node`` in floating point."""
    if isinstance(node, ast.Name):
        name = node.id
        return lambda v: v[name]
    if isinstance(node, ast.Constant):
        c = float(node.value)
        return lambda v: c
    if isinstance(node, ast.UnaryOp):
        f = _closure(node.operand)
        return (lambda v: -f(v)) if isinstance(node.op, ast.USub) else f
    left, right = _closure(node.left), _closure(node.right)  # type: ignore[attr-defined]
    op = _real_pow if isinstance(node.op, ast.Pow) else _BINOPS[type(node.op)]  # type: ignore[attr-defined]
    return lambda v: op(left(v), right(v))


@functools.lru_cache(maxsize=1024)
def _program(expr: str) -> tuple[Callable[[Mapping[str, Number]], Number], tuple[str, ...]]:
    """``(evaluate, names)`` of a validated expression, built once per distinct expression."""
    body = _parse(expr)
    _check_tree(expr, body, 0, [0])
    names = tuple(dict.fromkeys(n.id for n in ast.walk(body) if isinstance(n, ast.Name)))
    return _closure(body), names


def _evaluate(expr: str, values: Mapping[str, Number]) -> Number:
    """Value of ``expr`` in floating point (complex values pass through, for complex steps)."""
    fn, _ = _program(expr)
    try:
        v = fn(values)
    except ZeroDivisionError:
        raise ParameterError(f"parameter expression {expr!r} divides by zero") from None
    except OverflowError:
        raise ParameterError(f"parameter expression {expr!r} overflows (its value is too large)") from None
    except ArithmeticError as exc:
        raise ParameterError(f"parameter expression {expr!r} {exc}") from None
    except KeyError as exc:
        raise ParameterError(f"parameter expression {expr!r}: name {exc.args[0]!r} has no value") from None
    finite = cmath.isfinite(v) if isinstance(v, complex) else math.isfinite(v)
    if not finite:
        raise ParameterError(f"parameter expression {expr!r} is not finite ({v!r})")
    return v


@dataclass(frozen=True)
class AffineTie:
    """A parameter as an affine function of base parameters: ``constant + sum k * value(base)``.

    ``terms`` holds ``(base, k)`` pairs, each base once, in the order the expression first names
    it, without zero coefficients; a base parameter is ``AffineTie(0, ((name, 1),))``. What the
    compiled costs hold instead of an expression (:func:`affine_tie`).
    """

    constant: float
    terms: tuple[tuple[str, float], ...]


def affine_tie(params: Mapping[str, Parameter], name: str) -> AffineTie | None:
    """The parameter ``name`` as an :class:`AffineTie` of base parameters, or None where it is not affine.

    Follows chains of ties (``R1 = Rw/2``, ``R2 = 3 * R1 / 4``) and sums of them (a circuit's
    last share ``1 - s_1 - s_2``, :mod:`rczone.models.multizone`): numbers, names, ``+``, ``-``,
    products with a number and divisions by a nonzero number. A product or quotient of two
    parameters, a power or a non-finite constant is None. Compiled costs use this to go from the
    free parameters to every element value and heat-input gain without evaluating expressions.
    """
    memo: dict[str, tuple[float, dict[str, float]] | None] = {}

    def of(name: str) -> tuple[float, dict[str, float]] | None:
        # once per parameter: a chain of ties that each use the previous one twice (S1 = S0*S0,
        # S2 = S1*S1, ...) would otherwise be walked 2**n times
        if name not in memo:
            p = params[name]
            memo[name] = walk(ast.parse(p.expr, mode="eval").body) if p.is_tied else (0.0, {name: 1.0})
        return memo[name]

    def scaled(a: tuple[float, dict[str, float]], k: float) -> tuple[float, dict[str, float]]:
        return a[0] * k, {b: c * k for b, c in a[1].items()}

    def walk(node: ast.AST) -> tuple[float, dict[str, float]] | None:
        # the expressions were validated (and so bounded, and their chains by MAX_TIE_CHAIN) when
        # the parameters were declared
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
            return float(node.value), {}
        if isinstance(node, ast.Name):
            return of(node.id) if node.id in params else None
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            inner = walk(node.operand)
            return None if inner is None else scaled(inner, -1.0 if isinstance(node.op, ast.USub) else 1.0)
        if not isinstance(node, ast.BinOp):
            return None
        a, b = walk(node.left), walk(node.right)
        if a is None or b is None:
            return None
        if isinstance(node.op, (ast.Add, ast.Sub)):
            sign = 1.0 if isinstance(node.op, ast.Add) else -1.0
            terms = dict(a[1])
            for base, k in b[1].items():
                terms[base] = terms.get(base, 0.0) + sign * k
            return a[0] + sign * b[0], terms
        if isinstance(node.op, ast.Mult) and not (a[1] and b[1]):
            return scaled(b, a[0]) if not a[1] else scaled(a, b[0])
        if isinstance(node.op, ast.Div) and not b[1] and b[0] != 0.0:
            return scaled(a, 1.0 / b[0])
        return None

    found = walk(ast.Name(id=name)) if name in params else None
    if found is None:
        return None
    constant, terms = found
    kept = tuple((b, k) for b, k in terms.items() if k != 0.0)
    if not all(math.isfinite(v) for v in (constant, *(k for _, k in kept))):
        return None
    return AffineTie(constant, kept)


def proportional_base(params: Mapping[str, Parameter], name: str) -> tuple[float, str | None] | None:
    """``(k, base)`` with ``value(name) = k * value(base)`` for every value of ``base``.

    A base parameter is ``(1, name)``; a tie such as ``R1 = Rw/2`` is ``(0.5, "Rw")``, also
    through chains of ties; an expression of numbers only is ``(value, None)``. Anything else
    (a sum of parameters, a power, a product of two parameters) is None: the special case of
    :func:`affine_tie` that resistances and capacities, positive by construction, may take.
    """
    tie = affine_tie(params, name)
    if tie is None:
        return None
    if not tie.terms:
        return tie.constant, None
    if len(tie.terms) == 1 and tie.constant == 0.0:
        base, k = tie.terms[0]
        return k, base
    return None


MAX_TIE_CHAIN = 32
"""Longest chain of ties (a tie of a tie of ...) accepted; real models chain two or three."""


def check_declarations(params: Mapping[str, Parameter]) -> tuple[str, ...]:
    """Validate tied expressions and return an evaluation order of the tied parameters.

    Raises :class:`ParameterError` for an expression naming an undeclared parameter, for a
    cycle of ties, or for a chain of ties longer than :data:`MAX_TIE_CHAIN`. No recursion: a
    hostile file's chain of thousands of ties is one line, not a ``RecursionError``.
    """
    order: list[str] = []
    state: dict[str, int] = {}
    depth: dict[str, int] = {}

    def deps(name: str) -> tuple[str, ...]:
        p = params[name]
        if p.expr is None:
            return ()
        out = expression_names(p.expr)
        for dep in out:
            if dep not in params:
                raise ParameterError(
                    f"parameter {name!r} = {p.expr!r} names unknown parameter {dep!r}; "
                    + did_you_mean(dep, params)
                )
        return out

    for root in params:
        if state.get(root) == 2:
            continue
        stack: list[tuple[str, int]] = [(root, 0)]
        state[root] = 1
        while stack:
            name, i = stack[-1]
            ds = deps(name)
            if i < len(ds):
                stack[-1] = (name, i + 1)
                dep = ds[i]
                if state.get(dep) == 1:
                    chain = [n for n, _ in stack]
                    chain = chain[chain.index(dep) :]
                    raise ParameterError("tied parameters form a cycle: " + " -> ".join((*chain, dep)))
                if state.get(dep) != 2:
                    if len(stack) > MAX_TIE_CHAIN:
                        raise ParameterError(
                            f"parameter {root!r} is a chain of more than {MAX_TIE_CHAIN} ties"
                            " (rczone.network.parameters.MAX_TIE_CHAIN); tie parameters to base ones directly"
                        )
                    state[dep] = 1
                    stack.append((dep, 0))
                continue
            stack.pop()
            d = 1 + max((depth[x] for x in ds), default=-1) if params[name].expr is not None else 0
            if d > MAX_TIE_CHAIN:
                raise ParameterError(
                    f"parameter {name!r} is a chain of more than {MAX_TIE_CHAIN} ties"
                    " (rczone.network.parameters.MAX_TIE_CHAIN); tie parameters to base ones directly"
                )
            depth[name] = d
            if params[name].expr is not None:
                order.append(name)
            state[name] = 2
    return tuple(order)


def resolve(
    params: Mapping[str, Parameter],
    theta: Mapping[str, float] | None = None,
    order: tuple[str, ...] | None = None,
) -> dict[str, float]:
    """Values of every parameter given the base values in ``theta``.

    Parameters
    ----------
    params : mapping of str to Parameter
        The declared parameters.
    theta : mapping of str to float, optional
        Values of base parameters; omitted ones take their declared ``value``.
    order : tuple of str, optional
        Evaluation order of tied parameters (from :func:`check_declarations`).

    Returns
    -------
    dict of str to float
        Every parameter's value in SI units.
    """
    theta = {} if theta is None else theta
    for name in theta:
        if name not in params:
            raise ParameterError(f"unknown parameter {name!r}; " + did_you_mean(name, params))
        if params[name].is_tied:
            raise ParameterError(
                f"parameter {name!r} is tied ({name} = {params[name].expr}); set the parameters"
                " it depends on instead"
            )
    values: dict[str, float] = {}
    for name, p in params.items():
        if p.is_tied:
            continue
        if name in theta:
            v = float(theta[name])
            _check_value(p, v)
        elif p.value is not None:
            v = p.value
        else:
            raise ParameterError(f"parameter {name!r} has no value: give it in theta or declare a default")
        values[name] = v
    values = evaluate_ties(params, values, order)
    for name, p in params.items():
        if p.is_tied:
            _check_value(p, values[name])
    return values


def evaluate_ties(
    params: Mapping[str, Parameter], base: Mapping[str, float | complex], order: tuple[str, ...] | None = None
) -> dict:
    """Add the values of tied parameters to ``base`` (no range checks; complex values allowed).

    Used directly for complex-step differentiation; :func:`resolve` checks the results.
    """
    values = dict(base)
    for name in order if order is not None else check_declarations(params):
        values[name] = _evaluate(params[name].expr, values)  # type: ignore[arg-type]
    return values
