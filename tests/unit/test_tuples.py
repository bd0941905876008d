"""No tuple of more than four elements crosses a function boundary in ``src/rczone`` (issue 20).

Longer groups of values travel as ``NamedTuple``s (``rczone.kernels.arrays`` has the pattern) and
are read by name. Three forms are caught, by the syntax tree: a ``return`` of a literal tuple of
more than four elements, a ``tuple[...]`` return annotation of more than four, and positional
unpacking of more than four names from a call or a variable (a literal tuple or a generator on
the right is local and allowed).
"""

from __future__ import annotations

import ast
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "src" / "rczone"
MOST = 4


def long_tuples(source: str, where: str = "<string>") -> list[str]:
    """Places in ``source`` where a tuple of more than :data:`MOST` elements crosses a function boundary."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            ann = node.returns
            if (
                isinstance(ann, ast.Subscript)
                and isinstance(ann.value, ast.Name)
                and ann.value.id == "tuple"
                and isinstance(ann.slice, ast.Tuple)
                and len(ann.slice.elts) > MOST
            ):
                found.append(
                    f"{where}:{node.lineno} {node.name} is annotated to return {len(ann.slice.elts)} values"
                )
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


def test_no_tuple_of_more_than_four_elements_crosses_a_function_boundary():
    found = []
    for path in sorted(SRC.rglob("*.py")):
        found += long_tuples(path.read_text(), str(path.relative_to(SRC.parent)))
    assert not found, "use a NamedTuple:\n" + "\n".join(found)


def test_the_check_finds_each_form():
    assert len(long_tuples("def f():\n    return 1, 2, 3, 4, 5\n")) == 1
    assert len(long_tuples("def f() -> tuple[int, int, int, int, int]:\n    pass\n")) == 1
    assert len(long_tuples("a, b, c, d, e = f()\n")) == 1
    assert len(long_tuples("a, b, c, d, e = problem.data\n")) == 1
    # four, a named tuple read by name, and a local literal are fine
    assert long_tuples("def f() -> tuple[int, int, int, int]:\n    return 1, 2, 3, 4\n") == []
    assert long_tuples("a, b, c, d, e = (x.a, x.b, x.c, x.d, x.e)\nt = f().t\n") == []
