"""Fuzzing the loaders of user files (issue 14): the only outcomes are a result or one line.

Each loader gets inputs made two ways: a valid file mutated byte by byte (deletions,
insertions, replacements, truncation, duplicated spans), and structures generated from
scratch. Whatever the input, the loader returns, or raises an :class:`~rczone.errors.RczoneError`
whose message is one line -- which the CLI prints as ``error: ...`` with exit code 2
(``tests/unit/cli``). Any other exception is a defect. ``make test`` runs a quick round per
loader; the ``slow`` round runs 10,000 inputs per loader.
"""

from __future__ import annotations

import tempfile
import tomllib
import warnings
from collections import Counter
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rczone.batch.manifest import parse_manifest, read_manifest
from rczone.data import parse_column_map, read_column_map
from rczone.errors import RczoneError
from rczone.models import ZoneModel, load_model
from rczone.models.modelfile import model_from_document
from rczone.workflow.reader import read_frame

QUICK, LONG = 60, 10_000


def _valid_log() -> bytes:
    t = np.arange(40) * 300.0 + 1.3e9
    frame = pd.DataFrame(
        {
            "time": t,
            "Ti": 21 + np.sin(t / 3e3),
            "To": 10.0 + 0 * t,
            "Ts": 16.0 + 0 * t,
            "m": 0.1 + 0 * t,
            "Q": 50.0 + 0 * t,
            "Tsd": 22.0 + 0 * t,
        }
    )
    return frame.to_csv(index=False).encode()


VALID_LOG = _valid_log()
VALID_MAP = b"""name = "room"
na_values = ["---"]
[time]
column = "Timestamp"
format = "auto"
timezone = "America/New_York"
[columns]
Ti = { column = "T room", unit = "degF" }
To = "OAT"
m = { column = "flow", unit = "cfm" }
Q = { value = 50 }
[surroundings]
Tn1 = "T next"
[resample]
step = 300
"""
VALID_MANIFEST = b"""methods = ["ls", "ml"]
optimizer = "nelder-mead"
n_starts = 2
constants = { Q = 50.0 }
[[zone]]
id = "room"
data = "C"
methods = ["ls"]
[[generate]]
prefix = "g"
seasons = ["autumn"]
modes = ["forced", "closed-loop"]
seeds = "0..3"
"""
VALID_MODEL = b"""name = "office"
boundaries = ["To"]
outputs = ["Ti"]
resistors = [["Ti", "Te", "Rie"], ["Te", "To", "Rea"], ["Ti", "Tm", "R1"], ["Tm", "To", "R1"]]
[nodes]
Ti = { capacity = "Ci", description = "air" }
Te = "Ce"
Tm = {}
[heat_inputs]
Ph = "Ti"
Ps = { to = { Ti = "Aw", Te = 0.3 }, unit = "W/m2" }
[[supply_air]]
node = "Ti"
flow = "m"
temperature = "Ts"
cp = 1005
[parameters]
Ci = { value = 1.2, unit = "MJ/K", bounds = [0.01, 100] }
Ce = { value = 15, unit = "MJ/K" }
Rie = { value = 2, unit = "K/kW" }
Rea = { value = 20, unit = "K/kW", fixed = true }
Rw = { value = 8, unit = "K/kW" }
R1 = { expr = "Rw/2" }
Aw = { value = 2, unit = "m2", bounds = [0, 50] }
[inputs]
Ph = { default = 0, description = "heater, W" }
"""


def _valid_saved() -> bytes:
    import json

    zm = load_model("second-order-paper").with_values({"Rw": 0.02}, {"sigma_v": 0.05}, method="ml")
    return json.dumps(zm.to_dict()).encode()


VALID_SAVED = _valid_saved()


@st.composite
def mutated(draw, valid: bytes) -> bytes:
    """``valid`` with a few random edits."""
    data = bytearray(valid)
    for _ in range(draw(st.integers(1, 6))):
        op = draw(st.sampled_from(["delete", "insert", "replace", "truncate", "duplicate"]))
        i = draw(st.integers(0, max(0, len(data) - 1)))
        j = min(len(data), i + draw(st.integers(1, 40)))
        if op == "delete":
            del data[i:j]
        elif op == "insert":
            data[i:i] = draw(
                st.binary(min_size=1, max_size=12)
                | st.sampled_from(
                    [b"[", b"]", b"\n", b'"', b"=", b",", b"nan", b"-1e400", b"\xe9", b";", b"{", b"\x00"]
                )
            )
        elif op == "replace":
            data[i:j] = draw(st.binary(max_size=j - i + 2))
        elif op == "truncate":
            del data[i:]
        else:
            data[i:i] = data[i:j] * draw(st.integers(1, 30))
    return bytes(data)


scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**20), 10**20),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=12),
    st.sampled_from(
        ["Ti", "To", "degF", "cfm", "kW", "UTC", "18:00", "ls", "ml", "autumn", "forced", "C", "0..3"]
    ),
)
structures = st.recursive(
    scalars,
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.dictionaries(
            st.text(max_size=8)
            | st.sampled_from(
                [
                    "columns",
                    "time",
                    "zone",
                    "id",
                    "data",
                    "virtual",
                    "seeds",
                    "Ti",
                    "column",
                    "unit",
                    "value",
                    "step",
                    "generate",
                    "methods",
                    "model",
                    "nodes",
                    "resistors",
                    "parameters",
                    "heat_inputs",
                    "supply_air",
                    "capacity",
                    "expr",
                    "bounds",
                    "fixed",
                    "network",
                    "theta",
                    "format",
                ]
            ),
            inner,
            max_size=5,
        )
    ),
    max_leaves=20,
)


OUTCOMES: Counter[str] = Counter()


def _one_line_or_result(call) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            call()
        except RczoneError as exc:
            assert "\n" not in str(exc), str(exc)
            OUTCOMES["one-line error"] += 1
        except FileNotFoundError:
            OUTCOMES["file not found"] += 1  # the CLI prints one line (a mutated map may name a missing file)
        else:
            OUTCOMES["result"] += 1


def _in_file(suffix: str, content: bytes, call) -> None:
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / f"input{suffix}"
        path.write_bytes(content)
        _one_line_or_result(lambda: call(path))


def _fuzz(strategy, n: int, check) -> None:
    @settings(max_examples=n, deadline=None, suppress_health_check=list(HealthCheck), database=None)
    @given(strategy)
    def run(x):
        check(x)

    run()


def _log(content: bytes) -> None:
    _in_file(".csv", content, read_frame)


def _map(content: bytes) -> None:
    _in_file(".toml", content, read_column_map)


def _manifest(content: bytes) -> None:
    _in_file(".toml", content, read_manifest)


def _model(content: bytes) -> None:
    _in_file(".toml", content, load_model)


def _saved(content: bytes) -> None:
    _in_file(".json", content, load_model)


def _model_structure(doc) -> None:
    _one_line_or_result(lambda: model_from_document(doc if isinstance(doc, dict) else {"nodes": doc}))


def _saved_structure(doc) -> None:
    if isinstance(doc, dict):
        doc = {"format": "rczone-model/1", **doc}
    _one_line_or_result(lambda: ZoneModel.from_dict(doc))


def _map_structure(doc) -> None:
    _one_line_or_result(lambda: parse_column_map(doc if isinstance(doc, dict) else {"columns": doc}))


def _manifest_structure(doc) -> None:
    _one_line_or_result(
        lambda: parse_manifest(doc if isinstance(doc, dict) else {"zone": doc}, Path("m.toml"))
    )


def _frames(draw_cols):
    names = st.sampled_from(["time", "Ti", "To", "Ts", "m", "Q", "Tsd", "Tf", "x", "Ti "])
    values = st.one_of(
        st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=6), st.integers(-(10**12), 10**14)
    )
    return st.dictionaries(names, st.lists(values, min_size=0, max_size=30), min_size=1, max_size=8)


def _frame_file(cols: dict) -> None:
    n = max(len(v) for v in cols.values())
    frame = pd.DataFrame({k: pd.Series(v + [None] * (n - len(v)), dtype=object) for k, v in cols.items()})
    _log(frame.to_csv(index=False).encode())


def test_valid_inputs_load():
    """The seeds of the mutations are valid (so mutations explore near valid files)."""
    with tempfile.TemporaryDirectory() as d:
        (Path(d) / "log.csv").write_bytes(VALID_LOG)
        (Path(d) / "map.toml").write_bytes(VALID_MAP)
        (Path(d) / "m.toml").write_bytes(VALID_MANIFEST)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            assert len(read_frame(Path(d) / "log.csv")) == 40
        assert read_column_map(Path(d) / "map.toml").step == 300
        assert len(read_manifest(Path(d) / "m.toml").tasks) == 1 + 8 * 2
        (Path(d) / "model.toml").write_bytes(VALID_MODEL)
        (Path(d) / "saved.json").write_bytes(VALID_SAVED)
        assert load_model(Path(d) / "model.toml").network.state_names == ("Ti", "Te")
        assert load_model(Path(d) / "saved.json").theta["Rw"] == 0.02
    assert tomllib.loads(VALID_MAP.decode())


CASES = {
    "trend-log-mutated": (mutated(VALID_LOG), _log),
    "trend-log-generated": (_frames(None), _frame_file),
    "column-map-mutated": (mutated(VALID_MAP), _map),
    "column-map-generated": (structures, _map_structure),
    "manifest-mutated": (mutated(VALID_MANIFEST), _manifest),
    "manifest-generated": (structures, _manifest_structure),
    "model-file-mutated": (mutated(VALID_MODEL), _model),
    "model-file-generated": (structures, _model_structure),
    "saved-model-mutated": (mutated(VALID_SAVED), _saved),
    "saved-model-generated": (structures, _saved_structure),
}


@pytest.mark.parametrize("case", list(CASES))
def test_fuzz_quick(case):
    strategy, check = CASES[case]
    OUTCOMES.clear()
    _fuzz(strategy, QUICK, check)
    print(f"{case}: {dict(OUTCOMES)}")


@pytest.mark.slow
@pytest.mark.parametrize("case", list(CASES))
def test_fuzz_long(case):
    strategy, check = CASES[case]
    OUTCOMES.clear()
    _fuzz(strategy, LONG // 2, check)  # two cases (mutated, generated) per loader: 10,000 inputs each
    print(f"{case}: {dict(OUTCOMES)}")
