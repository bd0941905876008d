"""Named physical parameters of an RC network, tied parameters and their resolution.

A parameter is either *base* (a value the user or an optimizer supplies) or *tied*
(an arithmetic expression over other parameters, such as the paper's ``R1 = Rw/2``).
:func:`resolve` turns a mapping of base values into the value of every parameter,
checking names, signs and expressions on the way. It never mutates its inputs.
"""

from __future__ import annotations

import ast
import functools
import math
import operator
from collections.abc import Mapping
from dataclasses import dataclass
from types import CodeType

from rczone.errors import ParameterError, did_you_mean

#: Kinds of parameter; ``resistance`` and ``capacitance`` must be strictly positive.
KINDS = ("resistance", "capacitance", "gain", "other")

_UNITS = {"resistance": "K/W", "capacitance": "J/K", "gain": "1", "other": ""}

_BINOPS = {
    ast.Add: operator.add,
    ast.Sub: operator.sub,
    ast.Mult: operator.mul,
    ast.Div: operator.truediv,
    ast.Pow: operator.pow,
}
_UNOPS = {ast.USub: operator.neg, ast.UAdd: operator.pos}


@dataclass(frozen=True)
class Parameter:
    """One named parameter of a network.

    Parameters
    ----------
    name : str
        Identifier used by the network elements and in ``theta`` mappings.
    kind : {"resistance", "capacitance", "gain", "other"}
        Physical role; resistances and capacitances must be > 0.
    value : float, optional
        Default (construction) value in SI units, used when ``theta`` omits it.
    expr : str, optional
        Arithmetic expression over other parameters (``"Rw/2"``). A tied parameter
        cannot also be given in ``theta``.
    unit : str, optional
        SI unit, defaults from ``kind`` (K/W, J/K, 1).
    description : str
        Free text for reports.
    """

    name: str
    kind: str = "other"
    value: float | None = None
    expr: str | None = None
    unit: str | None = None
    description: str = ""

    def __post_init__(self) -> None:
        if not self.name.isidentifier():
            raise ParameterError(f"parameter name {self.name!r} is not a valid identifier")
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
            object.__setattr__(self, "value", float(self.value))
            _check_value(self, self.value)

    @property
    def is_tied(self) -> bool:
        """True when the parameter is defined by an expression."""
        return self.expr is not None


def _check_value(p: Parameter, v: float) -> None:
    if not math.isfinite(v):
        raise ParameterError(f"parameter {p.name!r} = {v!r} is not finite")
    if p.kind in ("resistance", "capacitance") and v <= 0.0:
        raise ParameterError(
            f"parameter {p.name!r} = {v:g} {p.unit}: a {p.kind} must be > 0"
            " (use a very small or very large value to approximate a short or an open)"
        )


def expression_names(expr: str) -> tuple[str, ...]:
    """Names used in a parameter expression, validating its syntax.

    Only numbers, names, ``+ - * / **`` and parentheses are allowed.
    """
    try:
        tree = ast.parse(expr, mode="eval")
    except SyntaxError as exc:
        raise ParameterError(f"invalid parameter expression {expr!r}: {exc.msg}") from None
    names: list[str] = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Name):
            names.append(node.id)
        elif not isinstance(
            node,
            (ast.Expression, ast.BinOp, ast.UnaryOp, ast.Constant, ast.Load, *_BINOPS, *_UNOPS),
        ):
            raise ParameterError(
                f"parameter expression {expr!r} uses {type(node).__name__}; only numbers,"
                " parameter names, + - * / ** and parentheses are allowed"
            )
        if isinstance(node, ast.Constant) and not isinstance(node.value, (int, float)):
            raise ParameterError(f"parameter expression {expr!r} contains a non-number")
    return tuple(dict.fromkeys(names))


@functools.lru_cache(maxsize=1024)
def _compiled(expr: str) -> CodeType:
    """Byte code of ``expr``, compiled once per distinct expression.

    The expression is validated first (:func:`expression_names`: only numbers, names and
    arithmetic), so evaluating it with no builtins cannot do anything but arithmetic.
    """
    expression_names(expr)
    return compile(ast.parse(expr, mode="eval"), f"<parameter expression {expr!r}>", "eval")


def _evaluate(expr: str, values: Mapping[str, float | complex]) -> float | complex:
    try:
        v = eval(_compiled(expr), {"__builtins__": {}}, values)  # validated arithmetic only
    except ZeroDivisionError:
        raise ParameterError(f"parameter expression {expr!r} divides by zero") from None
    except NameError as exc:
        raise ParameterError(f"parameter expression {expr!r}: {exc}") from None
    return v if isinstance(v, complex) else float(v)


def proportional_base(params: Mapping[str, Parameter], name: str) -> tuple[float, str | None] | None:
    """``(k, base)`` with ``value(name) = k * value(base)`` for every value of ``base``.

    A base parameter is ``(1, name)``; a tie such as ``R1 = Rw/2`` is ``(0.5, "Rw")``, also
    through chains of ties; an expression of numbers only is ``(value, None)``. Anything else
    (a sum of parameters, a power, a product of two parameters) is None. Compiled costs use
    this to go from the free parameters to every element value without evaluating
    expressions.
    """

    def walk(node: ast.AST) -> tuple[float, str | None] | None:
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)):
            return float(node.value), None
        if isinstance(node, ast.Name):
            p = params.get(node.id)
            if p is None:
                return None
            return walk(ast.parse(p.expr, mode="eval").body) if p.is_tied else (1.0, node.id)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            inner = walk(node.operand)
            if inner is None:
                return None
            return (-inner[0] if isinstance(node.op, ast.USub) else inner[0]), inner[1]
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Mult, ast.Div)):
            a, b = walk(node.left), walk(node.right)
            if a is None or b is None or (a[1] is not None and b[1] is not None):
                return None
            if isinstance(node.op, ast.Mult):
                return a[0] * b[0], a[1] or b[1]
            if b[1] is not None or b[0] == 0.0:
                return None
            return a[0] / b[0], a[1]
        return None

    p = params[name]
    return walk(ast.parse(p.expr, mode="eval").body) if p.is_tied else (1.0, name)


def check_declarations(params: Mapping[str, Parameter]) -> tuple[str, ...]:
    """Validate tied expressions and return an evaluation order of the tied parameters.

    Raises :class:`ParameterError` for an expression naming an undeclared parameter or
    for a cycle of ties.
    """
    order: list[str] = []
    state: dict[str, int] = {}

    def visit(name: str, chain: tuple[str, ...]) -> None:
        if state.get(name) == 2:
            return
        if state.get(name) == 1:
            raise ParameterError("tied parameters form a cycle: " + " -> ".join((*chain, name)))
        state[name] = 1
        p = params[name]
        if p.expr is not None:
            for dep in expression_names(p.expr):
                if dep not in params:
                    raise ParameterError(
                        f"parameter {name!r} = {p.expr!r} names unknown parameter {dep!r}; "
                        + did_you_mean(dep, params)
                    )
                visit(dep, (*chain, name))
            order.append(name)
        state[name] = 2

    for name in params:
        visit(name, ())
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
