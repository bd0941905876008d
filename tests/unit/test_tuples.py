"""No tuple of more than four elements crosses a function boundary in ``src/rczone`` (issue 20).

Longer groups of values travel as ``NamedTuple``s (``rczone.kernels.arrays`` has the pattern) and
are read by name. The syntax tree is checked for these forms:

* anywhere in ``src/rczone``: a ``return`` of a literal tuple of more than four elements, a
  ``tuple[...]`` or ``Tuple[...]`` return annotation of more than four (``tuple[str, ...]``, a
  sequence of names, is one element repeated), and positional unpacking of more than four
  names from a call or a variable (a literal tuple or a generator on the right is local and
  allowed);
* in ``src/rczone/kernels`` (the compiled core, where options cannot be keyword-only because numba
  dispatches on positions): a function, compiled or not, with more than :data:`MOST_POSITIONAL`
  positional parameters. An argument list is a tuple too: past eight, the arrays travel as the
  named groups of ``rczone.kernels.arrays`` (``Assembled``, ``Discretization``, ``Interval``,
  ``Dynamics``, ...). The style guide's limit outside ``kernels/`` is about eight parameters as
  well, there with options keyword-only.

:data:`NOT_YET` names the kernel functions that still take more, with the reason; each entry must
still be one (the list only shrinks).
"""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "src" / "rczone"
MOST = 4
MOST_POSITIONAL = 8

#: Kernel functions with more positional parameters, not folded yet (file relative to ``src``: names).
#: ``adjoint.py`` is another engineer's module. The two of ``rc2.py`` cost time as
#: named tuples (measured against the positional form, interleaved, issue 20): numba's dispatcher
#: types a ``NamedTuple`` argument in Python, about 0.7 us each against 0.1 us for an array, and
#: ``nll_rc2`` (through ``estimation.kalman.kalman_nll_rc2``) and ``simulate_rc2`` are called from
#: Python per evaluation (11.7 -> 14.1 us, 49 -> 52 us). Binding their callers to the compiled
#: specialization once (as ``kernels.problem.value_kernel`` does) would remove that.
NOT_YET = {
    "rczone/kernels/adjoint.py": {"nll_rc2_adjoint"},
    "rczone/kernels/rc2.py": {"nll_rc2", "simulate_rc2"},
}


def _tuple_length(node: ast.expr) -> int | None:
    """Elements of a ``tuple[...]`` / ``Tuple[...]`` annotation (None for another annotation)."""
    if (
        isinstance(node, ast.Subscript)
        and isinstance(node.value, (ast.Name, ast.Attribute))
        and (node.value.id if isinstance(node.value, ast.Name) else node.value.attr) in ("tuple", "Tuple")
        and isinstance(node.slice, ast.Tuple)
    ):
        return len(node.slice.elts)
    return None


def long_tuples(source: str, where: str = "<string>") -> list[str]:
    """Places in ``source`` where a tuple of more than :data:`MOST` elements crosses a function boundary."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            k = _tuple_length(node.returns) if node.returns is not None else None
            if k is not None and k > MOST:
                found.append(f"{where}:{node.lineno} {node.name} is annotated to return {k} values")
        elif (
            isinstance(node, ast.Return) and isinstance(node.value, ast.Tuple) and len(node.value.elts) > MOST
        ):
            found.append(f"{where}:{node.lineno} returns a tuple of {len(node.value.elts)}")
        elif isinstance(node, ast.Assign):
            for target in node.targets:
                if (
                    isinstance(target, ast.Tuple)
                    and len(target.elts) > MOST
                    and not isinstance(node.value, (ast.Tuple, ast.GeneratorExp, ast.ListComp, ast.List))
                ):
                    found.append(f"{where}:{node.lineno} unpacks {len(target.elts)} values by position")
    return found


def long_signatures(source: str, where: str = "<string>") -> dict[str, str]:
    """Functions of ``source`` with more than :data:`MOST_POSITIONAL` positional parameters, by name."""
    found = {}
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            positional = [
                a.arg for a in node.args.posonlyargs + node.args.args if a.arg not in ("self", "cls")
            ]
            if len(positional) > MOST_POSITIONAL:
                found[node.name] = (
                    f"{where}:{node.lineno} {node.name} takes {len(positional)} positional parameters"
                )
    return found


def test_no_tuple_of_more_than_four_elements_crosses_a_function_boundary():
    found = []
    for path in sorted(SRC.rglob("*.py")):
        found += long_tuples(path.read_text(), str(path.relative_to(SRC.parent)))
    assert not found, "use a NamedTuple:\n" + "\n".join(found)


def test_no_kernel_takes_more_than_eight_positional_parameters():
    found, stale = [], []
    for path in sorted((SRC / "kernels").rglob("*.py")):
        where = str(path.relative_to(SRC.parent))
        long = long_signatures(path.read_text(), where)
        pending = NOT_YET.get(where, set())
        found += [line for name, line in long.items() if name not in pending]
        stale += [f"{where} {name}" for name in sorted(pending - set(long))]
    assert not found, "group the arrays in NamedTuples of rczone.kernels.arrays:\n" + "\n".join(found)
    assert not stale, "folded: remove from NOT_YET:\n" + "\n".join(stale)


def test_the_check_finds_each_form():
    assert len(long_tuples("def f():\n    return 1, 2, 3, 4, 5\n")) == 1
    assert len(long_tuples("def f() -> tuple[int, int, int, int, int]:\n    pass\n")) == 1
    assert len(long_tuples("def f() -> typing.Tuple[int, int, int, int, int]:\n    pass\n")) == 1
    assert len(long_tuples("a, b, c, d, e = f()\n")) == 1
    assert len(long_tuples("a, b, c, d, e = problem.data\n")) == 1
    # four, a named tuple read by name, and a local literal are fine
    assert long_tuples("def f() -> tuple[int, int, int, int]:\n    return 1, 2, 3, 4\n") == []
    assert long_tuples("a, b, c, d, e = (x.a, x.b, x.c, x.d, x.e)\nt = f().t\n") == []


def test_the_check_finds_a_long_signature_compiled_or_not():
    nine = ", ".join(f"a{i}" for i in range(9))
    assert list(long_signatures(f"def f({nine}):\n    pass\n")) == ["f"]
    assert list(long_signatures(f"@njit(cache=True)\ndef g({nine}):\n    pass\n")) == ["g"]
    # eight, keyword-only options and ``self`` do not count
    eight = ", ".join(f"a{i}" for i in range(8))
    assert long_signatures(f"def f({eight}, *, foh=False):\n    pass\n") == {}
    assert long_signatures(f"class K:\n    def f(self, {eight}):\n        pass\n") == {}


def test_the_signature_rule_fails_on_the_positional_discretization_it_replaced():
    """The discretization's former signature (14 arrays and flags by position) is caught."""
    old = (
        "def interval_derivatives(A0, N, B0, M, dA0, dN, dB0, dM, keys, qc, dqc, scale, foh, noise):\n"
        "    pass\n"
    )
    new = "def interval_derivatives(mod, der, how):\n    pass\n"
    assert list(long_signatures(old)) == ["interval_derivatives"]
    assert long_signatures(new) == {}
