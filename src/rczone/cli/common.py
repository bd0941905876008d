"""Helpers shared by CLI commands: the model and the data a user names, outputs, exit codes.

Everything heavy is imported inside the functions, so that ``rczone --help`` stays fast.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rczone.cli.console import escape

if TYPE_CHECKING:  # pragma: no cover
    import pandas as pd
    from rich.console import Console

    from rczone.models import ZoneModel

#: A user's string (file, column or zone name) made safe to print through rich markup.
esc = escape

#: Exit codes of every command (documented in the README and in :func:`rczone.cli.main.main`).
EXIT_OK = 0
EXIT_CHECK_FAILED = 1  # rczone validate: a reference check failed
EXIT_USER_ERROR = 2  # a mistake in the input or an unwritable output: one line on stderr
EXIT_UNTRUSTED = 3  # a fit finished but is flagged untrustworthy (all outputs written)
EXIT_ZONES_FAILED = 4  # fit-many: some zones failed with their own errors (stored)
EXIT_INFRASTRUCTURE = 5  # fit-many: some tasks could not run (lost worker...); the next run retries
EXIT_INTERRUPTED = 130  # Ctrl-C

#: Options several commands share (declare a command's parameter with these types).
QuietOption = Annotated[
    bool,
    typer.Option(
        "--quiet",
        "-q",
        help="No progress on stderr (a bar with elapsed and remaining time on a terminal, elsewhere a line every 10 s).",
    ),
]
ColumnMapOption = Annotated[Path | None, typer.Option("--columns", help="TOML column map for trend logs.")]
ConstantsOption = Annotated[
    list[str] | None,
    typer.Option("--const", help="Hold an input constant, NAME=VALUE in SI units (repeatable), e.g. Q=50."),
]

HoldOption = Annotated[
    str,
    typer.Option(
        "--hold",
        metavar="zoh|foh",
        help="Inputs between samples: zoh (held, default) or foh (linear; pySIP's choice, matters on"
        " coarse data).",
    ),
]
BoundsOption = Annotated[
    list[str] | None,
    typer.Option(
        "--bounds",
        metavar="NAME=LO,HI",
        help="Search bounds NAME=LO,HI, repeatable: SI units as the fit table prints them (J/K, K/W,"
        " K), or a model file's unit after the numbers, e.g. Ci=1e5,5e9 or 'Ci=0.1,500 kWh/K'.",
    ),
]
FixOption = Annotated[
    list[str] | None,
    typer.Option(
        "--fix",
        metavar="NAME[=VALUE]",
        help="Hold a parameter, NAME or NAME=VALUE (repeatable): any R, C or gain, a noise level"
        " (sigma_v, sigma_w_Te) or an initial state (x0_Te); without a value, the model's; SI units"
        " or a model file's unit after the number ('Rea=20 K/kW').",
    ),
]

OptionsOption = Annotated[
    list[str] | None,
    typer.Option(
        "--option",
        metavar="NAME=VALUE",
        help="An option of the method, repeatable, e.g. --option prior_spread=0.5 for --method map or"
        " --option draws=500 for mcmc (`rczone methods` lists each method's options).",
    ),
]


def method_options(method: str, items: list[str] | None, **shorthands: object):
    """The options of ``method`` from ``--option NAME=VALUE`` and the shorthands given (``--draws``).

    A shorthand left at None was not given; one given to a method without that option is refused
    by the method (:meth:`rczone.estimation.methods.MethodOptions.of`), as is any unknown name.

    Returns
    -------
    MethodOptions
    """
    from rczone.estimation.methods import method_of

    meth = method_of(method)
    picked = {k: v for k, v in shorthands.items() if v is not None}
    if not items:
        return meth.make_options(picked)
    parsed = meth.options.parse(items, meth.name)
    return meth.make_options({**{k: getattr(parsed, k) for k in parsed.names()}, **picked})


MODEL_HELP = (
    "Model: a built-in name (`rczone models` lists them, e.g. second-order-paper, TiTe+heater+solar),"
    " a model file (.toml) or a model saved by --save-model (.json; its values are the start)."
)


def model(spec: str) -> ZoneModel:
    """The model a user names (built-in, model file or saved model)."""
    from rczone.models import load_model

    return load_model(spec)


def read_frame(path: Path, column_map: Path | None = None, zm: ZoneModel | None = None) -> pd.DataFrame:
    """A zone's data as a frame in rczone's default columns, read by its data source as the API reads it.

    ``path`` names a trend log (with its column map) or a built-in data set
    (:func:`rczone.workflow.datasource.data_source`); with the model ``zm``, a file without a
    column map is read by the model's signal names.
    """
    from rczone.workflow.datasource import data_source

    frame = data_source(path, column_map).frame(zm)
    note_ignored(frame, column_map, f"{zm.label if zm is not None else 'the model'} does not use")
    return frame


def note_ignored(frame: pd.DataFrame, column_map: Path | None, unused: str) -> None:
    """One quiet line on stderr naming the mapped channels the model does not use (they are ignored).

    ``unused`` ends the sentence "the map maps Ps, which ...": ``"TiTe does not use"``.
    """
    from rczone.errors import printable

    ignored = frame.attrs.get("ignored_channels")
    if ignored and column_map is not None:
        names = ", ".join(map(str, ignored))
        typer.echo(
            f"note: {printable(column_map.name)} maps {printable(names)}, which {printable(unused)}: ignored",
            err=True,
        )


def check_seed(value: int) -> int:
    """A ``--seed``: an integer from 0 to 2**63 - 1 (:func:`rczone.validation.seed`)."""
    from rczone.validation import seed

    return seed(value, "--seed")


def split(text: str | None) -> list[str] | None:
    """``"a, b,c"`` -> ``["a", "b", "c"]``; None or empty -> None."""
    from rczone.files.text import nfkc

    return [nfkc(s.strip()) for s in text.split(",") if s.strip()] if text else None


def constants(items: Iterable[str] | None) -> dict[str, float] | None:
    """``["Q=50", "Ts=20"]`` -> ``{"Q": 50.0, "Ts": 20.0}`` (SI units); None when none given."""
    from rczone.errors import ParameterError
    from rczone.files.text import nfkc

    out: dict[str, float] = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        try:
            if not sep or not name.strip():
                raise ValueError
            v = float(value)
            if not math.isfinite(v):
                raise ValueError
            out[nfkc(name.strip())] = v
        except ValueError:
            raise ParameterError(
                f"--const must be NAME=VALUE with a finite number in SI units, e.g. Q=50; got {item!r}"
            ) from None
    return out or None


def _number(text: str) -> float:
    v = float(text)
    if not math.isfinite(v):
        raise ValueError
    return v


def _unit_factor(name: str, unit: str, kinds: Mapping[str, str], option: str) -> float:
    """Factor to SI of ``unit`` for the parameter ``name``: the units a model file accepts for its kind."""
    from rczone.errors import ParameterError, did_you_mean
    from rczone.models.modelfile import PARAMETER_UNITS

    kind = kinds.get(name)
    if kind is None:
        raise ParameterError(
            f"{option} {name}: a unit is for a resistance, capacity or gain of the model; give {name} in SI"
            " units without one"
        )
    table = PARAMETER_UNITS[kind]
    if unit not in table:
        raise ParameterError(
            f"{option} {name}: {unit!r} is not a unit of a {kind} ({', '.join(table)}); {did_you_mean(unit, table)}"
        )
    return table[unit]


def _numbers_and_unit(text: str) -> tuple[list[float], str]:
    """``"0.5,50 kWh/K"`` -> ``([0.5, 50.0], "kWh/K")``; ValueError for anything but finite numbers."""
    numbers, _, unit = text.strip().partition(" ")
    return [_number(v) for v in numbers.split(",")], unit.strip()


def bounds(
    items: Iterable[str] | None, kinds: Mapping[str, str] | None = None
) -> dict[str, tuple[float, float]]:
    """``["Ci=1e5,5e9", "Rea=0.2,2000 K/kW"]`` -> ``{"Ci": (1e5, 5e9), "Rea": (2e-4, 2.0)}`` (SI).

    ``kinds`` (parameter name -> kind) allows a unit after the numbers, one a model file accepts for
    the parameter's kind; the order of the bounds is checked by the settings.
    """
    from rczone.errors import ParameterError
    from rczone.files.text import nfkc

    out: dict[str, tuple[float, float]] = {}
    for item in items or ():
        name, sep, pair = item.partition("=")
        name = nfkc(name.strip())
        try:
            values, unit = _numbers_and_unit(pair) if sep and name else ([], "")
            if len(values) != 2:
                raise ValueError
        except ValueError:
            raise ParameterError(
                "--bounds must be NAME=LO,HI with two finite numbers and an optional unit, e.g. Ci=1e5,5e9"
                f" or 'Ci=0.1,500 kWh/K'; got {item!r}"
            ) from None
        factor = _unit_factor(name, unit, kinds or {}, "--bounds") if unit else 1.0
        out[name] = (values[0] * factor, values[1] * factor)
    return out


def fixed(items: Iterable[str] | None, kinds: Mapping[str, str] | None = None) -> dict[str, float | None]:
    """``["sigma_v=0.01", "Rea", "Rie=2 K/kW"]`` -> ``{"sigma_v": 0.01, "Rea": None, "Rie": 0.002}``.

    None holds the model's value; ``kinds`` allows a unit after the number, as for :func:`bounds`.
    """
    from rczone.errors import ParameterError
    from rczone.files.text import nfkc

    out: dict[str, float | None] = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        name = nfkc(name.strip())
        try:
            values, unit = _numbers_and_unit(value) if sep else ([], "")
            if not name or len(values) != (1 if sep else 0):
                raise ValueError
        except ValueError:
            raise ParameterError(
                "--fix must be NAME or NAME=VALUE with a finite number and an optional unit, e.g."
                f" sigma_v=0.01 or 'Rea=20 K/kW'; got {item!r}"
            ) from None
        factor = _unit_factor(name, unit, kinds or {}, "--fix") if unit else 1.0
        out[name] = values[0] * factor if values else None
    return out


def parameter_kinds(*models: ZoneModel) -> dict[str, str]:
    """Name -> kind of the models' own parameters (what a unit in ``--bounds`` and ``--fix`` is checked against)."""
    return {n: p.kind for zm in models for n, p in zm.network.parameters.items()}


def free_list(items: Iterable[str] | None) -> list[str] | None:
    """Every ``--free`` given, each comma-separated, as one list; None when none given."""
    names = [n for item in items or () for n in split(item) or ()]
    return names or None


def out_console(json_out: Path | None) -> Console:
    """The console for the human-readable output: stderr when JSON goes to stdout (``--json -``,
    ``--json /dev/stdout`` or a link to it); unwrapped where it is not a terminal."""
    from rich.console import Console

    from rczone.cli.console import unwrapped
    from rczone.files.atomic import is_stream

    return unwrapped(Console(stderr=json_out is not None and is_stream(json_out)))


def write_json(json_out: Path | None, payload: Any) -> None:
    """Write ``payload`` to ``json_out`` atomically, or to stdout for ``-``."""
    if json_out is None:
        return
    from rczone.files.atomic import json_text, write_json_atomic, write_stdout

    if str(json_out) == "-":
        write_stdout(json_text(payload))
    else:
        write_json_atomic(json_out, payload)


def check_on_items(text: str | None, column_map: Path | None) -> list[tuple[str, Path | None]]:
    """``--check-on "a.csv,b.csv:b.toml"`` -> ``[("a.csv", column_map), ("b.csv", Path("b.toml"))]``.

    Each item is a file (or a built-in set) read with the fit's own column map, or ``FILE:MAP``
    read with its own map (a twin building whose trend log names its columns otherwise). A colon
    followed by something that does not end in ``.toml`` is part of the file's name.
    """
    out = []
    for item in split(text) or []:
        # the first colon after which a .toml path follows, not a drive letter's (C:/...)
        cut = next(
            (i for i, c in enumerate(item) if c == ":" and i > 1 and item[i + 1 :].lower().endswith(".toml")),
            None,
        )
        out.append((item[:cut], Path(item[cut + 1 :])) if cut is not None else (item, column_map))
    return out


def data_label(path: Path) -> str:
    """The name shown in titles: the file name without its folders, or the built-in set's name."""
    return Path(str(path)).name
