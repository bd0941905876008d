"""The stochastic parameters' names: built and read in one module, round trips, and nowhere else.

The meta-test reads every module of ``src/rczone`` (its syntax tree, not its text) and fails where
a string literal spells a prefix of a stochastic parameter's name (``sigma_v``, ``sigma_w_``,
``sigma_x0_``, ``x0_``, or the bare ``sigma_``) outside :mod:`rczone.network.stochastic`:

* a literal that starts with a prefix (``"sigma_v"``, ``n.startswith("x0_")``, ``"sigma_w_Ti"``);
* the piece of an f-string that ends with a prefix right before a field (``f"sigma_w_{s}"``);
* a ``startswith``/``removeprefix``/``split``-like call with a literal beginning ``sigma``/``x0``.

Docstrings and comments are not read (they document the names); prose inside a message
(``"... needs sigma_v > 0"``) is allowed because it neither builds nor parses a name. Two JSON field
names that merely begin like a prefix are listed in :data:`JSON_FIELDS`.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import rczone
from rczone.errors import ParameterError
from rczone.network import Parameter
from rczone.network.stochastic import (
    INITIAL_SPREAD,
    INITIAL_STATE,
    KINDS,
    MEASUREMENT_NOISE,
    PROCESS_NOISE,
    default_value,
    initial_spread_names,
    initial_state_names,
    is_noise_name,
    is_reserved,
    kind_of,
    measurement_noise_names,
    parameter_name,
    parse_name,
    process_noise_names,
    stochastic_parameter_names,
    target_of,
    unit_of,
)

ROOT = Path(rczone.__file__).resolve().parent
HOME = ROOT / "network" / "stochastic.py"

PREFIXES = ("sigma_v", "sigma_w_", "sigma_x0_", "x0_")
_ENDS_WITH_PREFIX = re.compile(r"(?<![A-Za-z0-9])(sigma_v_|sigma_w_|sigma_x0_|x0_|sigma_)$")
_PARSERS = {"startswith", "endswith", "removeprefix", "removesuffix", "split", "partition", "rpartition"}

#: JSON field names (a unit after the symbol), not parameter names: ``Calibration.to_dict`` and
#: ``control.noise.NoiseModel.to_dict`` write them.
JSON_FIELDS = {"sigma_v_K", "sigma_w_K_per_sqrt_s"}


def _docstrings(tree: ast.AST) -> set[int]:
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                out.add(id(body[0].value))
    return out


def offences(source: str) -> list[tuple[int, str]]:
    """``(line, literal)`` of every spelling of a stochastic prefix in ``source`` (see the module)."""
    tree = ast.parse(source)
    skip = _docstrings(tree)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in skip:
            text = node.value
            if (text.startswith(PREFIXES) or text == "sigma_") and text not in JSON_FIELDS:
                found.append((node.lineno, text))
        elif isinstance(node, ast.JoinedStr):
            for part, after in zip(node.values, node.values[1:]):
                if (
                    isinstance(part, ast.Constant)
                    and isinstance(after, ast.FormattedValue)
                    and _ENDS_WITH_PREFIX.search(part.value)
                ):
                    found.append((node.lineno, part.value))
        elif (
            isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in _PARSERS
        ):
            for arg in node.args:
                elts = arg.elts if isinstance(arg, ast.Tuple) else [arg]
                for e in elts:
                    if isinstance(e, ast.Constant) and str(e.value).startswith(("sigma", "x0")):
                        found.append((node.lineno, str(e.value)))
    return sorted(set(found))


def test_no_module_but_stochastic_spells_the_prefixes() -> None:
    bad = []
    for path in sorted(ROOT.rglob("*.py")):
        if path == HOME:
            continue
        for line, text in offences(path.read_text(encoding="utf-8")):
            bad.append(f"{path.relative_to(ROOT)}:{line}: {text!r}")
    assert not bad, "build or parse these names with rczone.network.stochastic:\n" + "\n".join(bad)


def test_the_json_field_exceptions_still_exist() -> None:
    sources = "".join(p.read_text(encoding="utf-8") for p in ROOT.rglob("*.py") if p != HOME)
    assert all(f'"{field}"' in sources for field in JSON_FIELDS)


@pytest.mark.parametrize(
    "source",
    [
        'names = [f"sigma_w_{s}" for s in states]',
        'x = {f"x0_{s}": 1.0}',
        'label = f"{a}: sigma_x0_{s}"',
        'ok = name.startswith("sigma_")',
        'ok = name.startswith(("sigma", "x0"))',
        'state = name.removeprefix("x0_")',
        'names = ("sigma_v",)',
        'NAME = "sigma_w_Ti"',
    ],
)
def test_the_scan_finds_a_prefix_spelled(source: str) -> None:
    assert offences(source)


@pytest.mark.parametrize(
    "source",
    [
        'def f():\n    """Builds ``sigma_w_<state>`` and ``x0_<state>``."""\n',
        'msg = f"noise {k!r}: a state estimator needs sigma_v > 0"',
        'key = "sigma_K"',
        'key = "sigma_v_K"',
        "x0 = 1.0  # the sigma_w_ of the comment",
        'raise ValueError(f"x0 must have shape ({n},)")',
    ],
)
def test_the_scan_leaves_docs_prose_and_other_names(source: str) -> None:
    assert offences(source) == []


# ----------------------------------------------------------------------------- the module itself


def test_one_output_has_one_plain_measurement_noise() -> None:
    assert measurement_noise_names(["Ti"]) == ("sigma_v",)
    assert parse_name("sigma_v") is not None
    assert (parse_name("sigma_v").kind, parse_name("sigma_v").target) == (MEASUREMENT_NOISE, None)


def test_several_outputs_have_one_measurement_noise_each() -> None:
    names = measurement_noise_names(["Ti", "Ts"])
    assert names == ("sigma_v_Ti", "sigma_v_Ts")
    assert [target_of(n) for n in names] == ["Ti", "Ts"]


@pytest.mark.parametrize("outputs", [("Ti",), ("Ti", "Tf"), ("Ti", "Tf", "T_slab")])
def test_every_name_round_trips_through_its_kind_and_target(outputs: tuple[str, ...]) -> None:
    states = ("Ti", "Tw", "Tm_2")
    names = stochastic_parameter_names(outputs, states)
    assert len(names) == len(set(names)) == (len(outputs) + 3 * len(states))
    for name in names:
        p = parse_name(name)
        assert p is not None and p.name == name
        assert parameter_name(p.kind, p.target) == name
    assert [kind_of(n) for n in names] == (
        [MEASUREMENT_NOISE] * len(outputs) + [PROCESS_NOISE] * 3 + [INITIAL_STATE] * 3 + [INITIAL_SPREAD] * 3
    )
    assert [target_of(n) for n in names[len(outputs) :]] == list(states) * 3


@pytest.mark.parametrize(
    "state",
    ["x0_a", "sigma_v", "sigma_w_b", "v", "w", "x0", "sigma_x0_c"],
)
def test_a_state_named_like_a_prefix_keeps_its_name(state: str) -> None:
    for kind, name in (
        (PROCESS_NOISE, process_noise_names([state])[0]),
        (INITIAL_STATE, initial_state_names([state])[0]),
        (INITIAL_SPREAD, initial_spread_names([state])[0]),
    ):
        assert (kind_of(name), target_of(name)) == (kind, state)
    out = measurement_noise_names([state, "Ti"])[0]
    assert (kind_of(out), target_of(out)) == (MEASUREMENT_NOISE, state)


@pytest.mark.parametrize(
    "name", ["Cr", "Rw", "sigma", "sigma_", "sigma_w_", "x0_", "sigma_x0_", "sigma_vx", "x0", "", "sigma_K"]
)
def test_other_names_are_not_stochastic(name: str) -> None:
    assert parse_name(name) is None
    assert kind_of(name) is None and default_value(name) is None and unit_of(name) is None
    assert not is_noise_name(name)


def test_reserved_prefixes_are_wider_than_the_names() -> None:
    assert is_reserved("sigma_foo") and is_reserved("x0_bar") and not is_reserved("Rx0_")
    assert is_reserved("sigma_foo", noise_only=True) and not is_reserved("x0_bar", noise_only=True)
    with pytest.raises(ParameterError, match="reserved"):
        Parameter("sigma_R", "resistance", 0.01)


def test_defaults_units_and_roles_are_those_of_the_estimation_table() -> None:
    assert default_value("sigma_v") == default_value("sigma_v_Ti") == 0.1
    assert default_value("sigma_w_Ti") == 1e-3
    assert default_value("sigma_x0_Tw") == 1.0
    assert default_value("x0_Tw") is None  # derived from the data
    assert [unit_of(n) for n in ("sigma_v", "sigma_w_Ti", "x0_Ti", "sigma_x0_Ti")] == [
        "K",
        "K/sqrt(s)",
        "degC",
        "K",
    ]
    assert {k: s.role for k, s in KINDS.items()} == {
        MEASUREMENT_NOISE: "noise",
        PROCESS_NOISE: "noise",
        INITIAL_STATE: "state",
        INITIAL_SPREAD: "noise",
    }
    assert is_noise_name("sigma_x0_Ti") and not is_noise_name("x0_Ti")


@pytest.mark.parametrize(("kind", "target"), [("bogus", "Ti"), (PROCESS_NOISE, None), (INITIAL_STATE, "")])
def test_a_name_needs_a_known_kind_and_a_state(kind: str, target: str | None) -> None:
    with pytest.raises(ParameterError, match=r"kind|state"):
        parameter_name(kind, target)
