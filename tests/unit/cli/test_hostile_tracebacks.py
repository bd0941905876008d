"""Issue 25, the tracebacks: every hostile input of the second campaign is one line and exit 2.

Big integers, chains of ties, mathtext in names, daylight-saving edges and far dates in a column
map, out-of-range numbers on the command line, and files that are not files (pipes, devices,
link loops, gzip bombs) each raised an exception from Python, NumPy, pandas or matplotlib.
Each case is checked through the CLI; each fails before any fit runs, so they are quick.
"""

from __future__ import annotations

import gzip
import os
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rczone.cli.main import main

BIG = 10**400
POSIX = pytest.mark.skipif(os.name == "nt", reason="pipes, devices and links as on POSIX")


def zone_frame(n: int = 120) -> pd.DataFrame:
    t = 1.3e9 + np.arange(n) * 300.0
    return pd.DataFrame({"time": t, "Ti": 21 + np.sin(t / 5e3), "To": 10 + np.cos(t / 7e3)})


def one_line_exit_2(args: list[str], capsys, pattern: str) -> str:
    assert main(args) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if not ln.startswith("warning: ")]
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in err, err
    assert re.search(pattern, err), err
    return err


@pytest.fixture
def data(tmp_path: Path) -> Path:
    zone_frame().to_csv(tmp_path / "z.csv", index=False)
    return tmp_path / "z.csv"


def model_text(extra_parameters: str = "", rie: str = "0.002") -> str:
    return f"""name = "room"
boundaries = ["To"]
outputs = ["Ti"]
resistors = [["Ti", "Te", "Rie"], ["Te", "To", "Rea"]]
[nodes]
Ti = "Ci"
Te = "Ce"
[parameters]
Ci = {{ value = 1e6, unit = "J/K" }}
Ce = {{ value = 1e7, unit = "J/K" }}
Rie = {{ value = {rie}, unit = "K/W" }}
Rea = {{ value = 0.02, unit = "K/W" }}
{extra_parameters}"""


MAP = '[columns]\nTi = "Ti"\nTo = "To"\n'


# ---- big integers ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "key"),
    [
        (f"air_density = {BIG}\n" + MAP, "air_density"),
        (MAP + f"[resample]\nstep = {BIG}\n", r"resample\.step"),
        (MAP + f"[resample]\nstep = 300\nmax_gap = {BIG}\n", r"resample\.max_gap"),
        (MAP + f'Q = {{ value = {BIG}, unit = "W" }}\n', r"columns\.Q\.value"),
    ],
    ids=["air_density", "step", "max_gap", "value"],
)
def test_big_integers_in_a_column_map(tmp_path, data, capsys, text, key):
    (tmp_path / "map.toml").write_text(text)
    one_line_exit_2(
        ["diagnose", str(data), "--model", "TiTe", "--columns", str(tmp_path / "map.toml")],
        capsys,
        key + r": an integer beyond 64 bits \(rczone.files.text.INT_LIMIT\)",
    )


def test_big_integers_in_model_files_and_manifests(tmp_path, data, capsys):
    (tmp_path / "m.toml").write_text(model_text(rie=str(BIG)))
    one_line_exit_2(["diagnose", str(data), "--model", str(tmp_path / "m.toml")], capsys, r"Rie\.value")
    saved = tmp_path / "saved.json"
    from rczone.models import load_model

    load_model("TiTe").save(saved)
    text = saved.read_text()
    saved.write_text(re.sub(r'("theta": \{\s*"[A-Za-z]+": )[^,}]+', rf"\g<1>{BIG}", text, count=1))
    one_line_exit_2(["diagnose", str(data), "--model", str(saved)], capsys, r"theta\.\w+: an integer beyond")
    (tmp_path / "batch.toml").write_text(f'constants = {{ Q = {BIG} }}\n[[zone]]\nid = "z"\ndata = "z.csv"\n')
    one_line_exit_2(["fit-many", str(tmp_path / "batch.toml")], capsys, r"constants\.Q: an integer beyond")


# ---- ties --------------------------------------------------------------------------------------


@pytest.mark.parametrize("direction", ["forward", "reversed"])
def test_a_chain_of_1500_ties_is_one_line(tmp_path, data, capsys, direction):
    n = 1500
    if direction == "forward":
        ties = 'T0 = { expr = "Rie*1" }\n' + "".join(
            f'T{i} = {{ expr = "T{i - 1}*1" }}\n' for i in range(1, n)
        )
    else:
        ties = f'T{n} = {{ expr = "Rie*1" }}\n' + "".join(
            f'T{i} = {{ expr = "T{i + 1}*1" }}\n' for i in range(n)
        )
    (tmp_path / "m.toml").write_text(model_text(ties))
    one_line_exit_2(
        ["diagnose", str(data), "--model", str(tmp_path / "m.toml")],
        capsys,
        r"chain of more than 32 ties \(rczone.network.parameters.MAX_TIE_CHAIN\)",
    )


def test_thirty_squaring_ties_are_quick(tmp_path, data, capsys):
    """Each tie uses the previous one twice: walked naively, 2**30 visits (a hang)."""
    ties = 'S0 = { expr = "Rie*1" }\n' + "".join(
        f'S{i} = {{ expr = "S{i - 1}*S{i - 1}" }}\n' for i in range(1, 31)
    )
    text = model_text(ties).replace('["Te", "To", "Rea"]', '["Te", "To", "S30"]')
    (tmp_path / "m.toml").write_text(text)
    one_line_exit_2(["diagnose", str(data), "--model", str(tmp_path / "m.toml")], capsys, r"'S30'")


# ---- mathtext ----------------------------------------------------------------------------------


def test_mathtext_in_names_reaches_the_figures_literally(tmp_path, capsys):
    name = "a$\\frac{$b"
    (tmp_path / "m.toml").write_text(model_text().replace('name = "room"', 'name = "a$\\\\frac{$b"'))
    data = tmp_path / f"{name}.csv"
    zone_frame().to_csv(data, index=False)
    rep = tmp_path / "rep"
    assert main(["predict", str(tmp_path / "m.toml"), str(data), "--report", str(rep)]) == 0, (
        capsys.readouterr()
    )
    assert (rep / "prediction.png").stat().st_size > 0
    assert name in (rep / "report.html").read_text()


# ---- time ----------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("setting", "pattern"),
    [
        ('start = "2014-03-09 02:30"', r"does not exist in America/New_York"),
        ('start = "2014-11-02 01:30"', r"is ambiguous in America/New_York"),
        ('end = "2262-06-01"', r"outside the dates rczone handles"),
        ('start = "1600-01-01"', r"outside the dates rczone handles"),
    ],
    ids=["nonexistent", "ambiguous", "2262", "1600"],
)
def test_column_map_start_and_end_at_the_edges(tmp_path, data, capsys, setting, pattern):
    (tmp_path / "map.toml").write_text(f'[time]\ntimezone = "America/New_York"\n{setting}\n' + MAP)
    one_line_exit_2(
        ["diagnose", str(data), "--model", "TiTe", "--columns", str(tmp_path / "map.toml")], capsys, pattern
    )


# ---- numbers on the command line ---------------------------------------------------------------


@pytest.mark.parametrize("command", ["fit", "select", "diagnose"])
def test_a_negative_seed(data, capsys, command):
    args = [command, str(data), "--seed", "-1"]
    if command == "select":
        args += ["--model", "Ti", "--model", "TiTe"]
    one_line_exit_2(args, capsys, r"--seed must be an integer from 0 to 2\*\*63 - 1, got -1")


@pytest.mark.parametrize("sigma", ["1e308", "1e-200", "1e-160", "inf"])
def test_diagnose_sigma_extremes(data, capsys, sigma):
    one_line_exit_2(["diagnose", str(data), "--model", "TiTe", "--sigma", sigma], capsys, r"sigma")


DESIGN = [
    "design",
    "--actuate",
    "Ts=12,35",
    "--condition",
    "m=0.1",
    "--condition",
    "To=16",
    "--condition",
    "Tsd=22",
]


@pytest.mark.parametrize(
    ("extra", "pattern"),
    [
        (["--min-hold", "1e-300"], r"at least 60 s .*MIN_HOLD_S"),
        (["--min-hold", "0.001"], r"at least 60 s"),
        (["--hours", "1e6"], r"more than the limit of 168 h .*MAX_DURATION_S"),
        (["--hours", "168", "--min-hold", "1"], r"more than the limit of 400 .*MAX_SEGMENTS"),
    ],
    ids=["1e-300", "tiny", "1e6-hours", "too-many-holds"],
)
def test_design_bounds(tmp_path, capsys, extra, pattern):
    one_line_exit_2([*DESIGN, *extra, "-o", str(tmp_path / "s.csv")], capsys, pattern)
    assert not (tmp_path / "s.csv").exists()


def test_a_non_finite_const(data, capsys):
    one_line_exit_2(
        ["diagnose", str(data), "--model", "TiTe", "--const", "Q=1e400"], capsys, r"finite number"
    )


# ---- files that are not files ----------------------------------------------------------------------


@POSIX
@pytest.mark.parametrize("role", ["data", "map", "model", "manifest"])
@pytest.mark.parametrize("kind", ["fifo", "device", "loop"])
def test_only_regular_files_are_read(tmp_path, data, capsys, role, kind):
    bad = tmp_path / f"bad.{'csv' if role == 'data' else 'toml'}"
    if kind == "fifo":
        os.mkfifo(bad)
        pattern = r"is a named pipe \(FIFO\), not a regular file"
    elif kind == "device":
        bad = Path("/dev/zero")
        pattern = r"is a device, not a regular file"
    else:
        bad.symlink_to(bad.name)
        pattern = r"symbolic link (that loops|loop)"
    args = {
        "data": ["diagnose", str(bad), "--model", "TiTe"],
        "map": ["diagnose", str(data), "--model", "TiTe", "--columns", str(bad)],
        "model": ["diagnose", str(data), "--model", str(bad)],
        "manifest": ["fit-many", str(bad), "--out", str(tmp_path / "out")],
    }[role]
    if role == "model" and kind == "device":
        pytest.skip("/dev/zero has no model file suffix")
    one_line_exit_2(args, capsys, pattern)


@POSIX
def test_a_link_loop_inside_a_manifest(tmp_path, data, capsys):
    (tmp_path / "loop.toml").symlink_to("loop.toml")
    (tmp_path / "batch.toml").write_text('model = "loop.toml"\n[[zone]]\nid = "z"\ndata = "z.csv"\n')
    one_line_exit_2(["fit-many", str(tmp_path / "batch.toml")], capsys, r"symbolic link")


def test_a_gzip_bomb_is_refused_at_the_limit(tmp_path, capsys):
    bomb = tmp_path / "z.csv.gz"
    with gzip.open(bomb, "wb", compresslevel=9) as fh:
        fh.write(b"time,Ti,To\n")
        block = b"1,2,3\n" * 200_000
        for _ in range(100):  # 120 MB of text, 120 kB on disk
            fh.write(block)
    one_line_exit_2(
        ["diagnose", str(bomb), "--model", "TiTe"],
        capsys,
        r"more than the limit of 100,000,000 .*MAX_DATA_BYTES",
    )


def test_a_data_file_over_the_size_limit(tmp_path, capsys, monkeypatch):
    import rczone.data.load as load

    monkeypatch.setattr(load, "MAX_DATA_BYTES", 1000)
    zone_frame().to_csv(tmp_path / "z.csv", index=False)
    one_line_exit_2(["diagnose", str(tmp_path / "z.csv"), "--model", "TiTe"], capsys, r"limit of 1,000")
    monkeypatch.setattr(load, "MAX_DATA_BYTES", 10**8)
    monkeypatch.setattr(load, "MAX_ROWS", 50)
    one_line_exit_2(["diagnose", str(tmp_path / "z.csv"), "--model", "TiTe"], capsys, r"120 rows.*MAX_ROWS")


def test_running_out_of_memory_is_one_line(data, capsys, monkeypatch):
    import rczone.workflow.reader as sources

    def exhausted(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr(sources, "read_frame", exhausted)
    one_line_exit_2(["diagnose", str(data), "--model", "TiTe"], capsys, r"out of memory")


# ---- hangs -------------------------------------------------------------------------------------------


def test_a_2000_node_chain_in_predict_is_refused_at_once(tmp_path, data, capsys):
    names = ["Ti"] + [f"N{i}" for i in range(1, 2000)]
    res = "".join(f'["{a}", "{b}", "R"],\n' for a, b in zip(names, [*names[1:], "To"]))
    nodes = "".join(f'{x} = "C"\n' for x in names)
    text = (
        f'name = "chain"\nboundaries = ["To"]\noutputs = ["Ti"]\nresistors = [\n{res}]\n[nodes]\n{nodes}'
        '[parameters]\nC = { value = 1e6, unit = "J/K" }\nR = { value = 0.001, unit = "K/W" }\n'
    )
    (tmp_path / "chain.toml").write_text(text)
    one_line_exit_2(
        ["predict", str(tmp_path / "chain.toml"), str(data)],
        capsys,
        r"2000 capacitive nodes .*limit of 200 \(rczone.network.network.MAX_STATES\)",
    )
