"""Issue 14, defects 5, 6, 7, 10, 11, 12: hostile files reach the user as one line and exit 2.

Each case was a traceback, a wrong result or a misleading message before (the issue's
adversarial campaign); the command is ``rczone diagnose`` or ``fit-many`` where loading is all
that is exercised, so the cases run in a fraction of a second each.
"""

from __future__ import annotations

import gzip
import re

import numpy as np
import pandas as pd
import pytest

from rczone.cli.main import main
from rczone.data import load_zone_data
from rczone.workflow.reader import read_frame


def zone_frame(n: int = 60) -> pd.DataFrame:
    t = 1.3e9 + np.arange(n) * 300.0
    return pd.DataFrame(
        {
            "time": t,
            "Ti": 21 + np.sin(t / 5e3),
            "To": 10 + np.cos(t / 7e3),
            "Ts": 16.0,
            "m": 0.1,
            "Q": 50.0,
            "Tsd": 22.0,
        }
    )


def one_line_exit_2(args: list[str], capsys, pattern: str) -> None:
    assert main(args) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if not ln.startswith("warning: ")]
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in err, err
    assert re.search(pattern, err), err


def test_a_truncated_gzip_log_is_an_error_not_aborted(tmp_path, capsys):
    raw = gzip.compress(zone_frame().to_csv(index=False).encode())
    (tmp_path / "z.csv.gz").write_bytes(raw[: len(raw) // 2])
    one_line_exit_2(["diagnose", str(tmp_path / "z.csv.gz")], capsys, r"the file ends early or is damaged")


@pytest.mark.parametrize(
    ("write", "pattern"),
    [
        (lambda p: p.mkdir(), r"is a folder, not a file"),
        (lambda p: p.write_bytes('[columns]\nTi = "caf\xe9"\n'.encode("latin-1")), r"is not UTF-8 text"),
        (lambda p: p.write_text("a = " + "[" * 3000 + "]" * 3000), r"nested more than 32 levels"),
        (
            lambda p: p.write_text('[columns]\nTi = "a"\nTo = "a"\n'),
            r"column 'a' is mapped to both 'Ti' and 'To'",
        ),
        (lambda p: p.write_text("columns = 5\n"), r"\[columns\] must be a table"),
        (
            lambda p: p.write_text('[columns]\nTi = "Ti"\nTsd = "Tsd"\n[resample]\nstep = 0.001\n'),
            r"more than the limit of 2,000,000 \(rczone.data.resample.MAX_SAMPLES\)",
        ),
    ],
    ids=["folder", "latin-1", "deep", "one-column-two-channels", "columns-not-a-table", "tiny-step"],
)
def test_hostile_column_maps(tmp_path, capsys, write, pattern):
    zone_frame().to_csv(tmp_path / "z.csv", index=False)
    write(tmp_path / "map.toml")
    one_line_exit_2(
        ["diagnose", str(tmp_path / "z.csv"), "--columns", str(tmp_path / "map.toml")], capsys, pattern
    )


def _edit_csv(text: str) -> str:
    return text


@pytest.mark.parametrize(
    ("make", "pattern"),
    [
        (lambda p: p.mkdir(), r"is a folder, not a file"),
        (lambda p: zone_frame().to_csv(p, index=False, sep=";"), r"the file seems separated by ';'"),
        (
            lambda p: p.write_text(zone_frame().to_csv(index=False).replace("Tsd", "Ti", 1)),
            r"column 'Ti' appears twice in the header \(columns 2 and 7\)",
        ),
        (
            lambda p: zone_frame().assign(time=lambda f: f.time * 1000).to_csv(p, index=False),
            r"look like milliseconds since 1970: set \[time\] format = \"milliseconds\"",
        ),
        (
            lambda p: (
                zone_frame()
                .assign(time=[f"2300-01-01T{h // 12:02d}:{h % 12 * 5:02d}:00" for h in range(60)])
                .to_csv(p, index=False)
            ),
            r"outside the years 1677 to 2262",
        ),
        (
            lambda p: zone_frame(4).to_csv(p, index=False),
            r"only 4 of 4 samples have a measured Ti",
        ),
        (
            lambda p: (
                zone_frame(1000).assign(Ti=lambda f: f.Ti.where(f.index % 100 == 0)).to_csv(p, index=False)
            ),
            r"only 10 of 1000 samples have a measured Ti; at least 30",
        ),
    ],
    ids=[
        "folder",
        "semicolon",
        "duplicate-header",
        "epoch-ms",
        "after-2262",
        "four-samples",
        "99pc-missing",
    ],
)
def test_hostile_trend_logs(tmp_path, capsys, make, pattern):
    make(tmp_path / "z.csv")
    one_line_exit_2(["diagnose", str(tmp_path / "z.csv")], capsys, pattern)


def test_a_gap_in_an_input_names_the_time_and_what_to_do():
    """Defect 12: a gap in an input said "not finite at sample 0" without time or hint."""
    from rczone.errors import DataError
    from rczone.estimation import Dataset

    f = zone_frame()
    u = f[["To", "Q"]].to_numpy(float).copy()
    u[7, 0] = np.nan
    with pytest.raises(
        DataError,
        match=r"input 'To' is missing \(NaN or infinite\) at 1 of 60 samples, first at t = 1300002100 s"
        r" \(2011-03-13T07:41:40Z\) \(sample 7\); inputs must be complete",
    ):
        Dataset(f.time.to_numpy(), u, None, f[["Ti"]].to_numpy(), ("To", "Q"))


def test_dates_after_2262_in_parquet(tmp_path):
    frame = zone_frame()
    frame["time"] = pd.date_range("2300-01-01", periods=len(frame), freq="5min", unit="s")
    frame.to_parquet(tmp_path / "z.parquet")
    with pytest.raises(Exception, match=r"outside the years 1677 to 2262") as info:
        read_frame(tmp_path / "z.parquet")
    assert "\n" not in str(info.value)


def test_a_log_without_q_loads_as_documented(tmp_path):
    """docs/data.md says Q is optional (50 W held constant): the default layout agreed only now."""
    zone_frame().drop(columns="Q").to_csv(tmp_path / "z.csv", index=False)
    frame = read_frame(tmp_path / "z.csv")
    assert "Q" not in frame and len(frame) == 60


def test_epoch_milliseconds_load_with_the_format_set(tmp_path):
    zone_frame().assign(time=lambda f: f.time * 1000).to_csv(tmp_path / "z.csv", index=False)
    (tmp_path / "map.toml").write_text(
        '[time]\nformat = "milliseconds"\n[columns]\n'
        + "".join(f'{c} = "{c}"\n' for c in ("Ti", "To", "Ts", "m", "Q", "Tsd"))
    )
    data = load_zone_data(tmp_path / "z.csv", tmp_path / "map.toml")
    np.testing.assert_array_equal(data.t, zone_frame().time.to_numpy())


def test_a_coarse_time_step_is_reported(tmp_path):
    """Defect 10: relative milliseconds read as seconds give 300,000 s steps; say so."""
    zone_frame().assign(time=lambda f: (f.time - f.time[0]) * 1000).to_csv(tmp_path / "z.csv", index=False)
    with pytest.warns(UserWarning, match=r"the median time step is 83.3 h.*milliseconds"):
        load_zone_data(tmp_path / "z.csv")


def test_markup_in_names_is_printed_literally(tmp_path, capsys):
    """Defect 7: `zone temp [degf]` lost its unit in messages printed through rich."""
    frame = zone_frame().rename(columns={"Ti": "zone temp [degf]"})
    frame.to_csv(tmp_path / "z.csv", index=False)
    (tmp_path / "map.toml").write_text(
        '[columns]\nTi = { column = "zone temp [degf]", unit = "degC" }\nTo = "To"\nTs = "Ts"\nm = "m"\nQ = "Q"\nTsd = "Tsd"\n'
    )
    (tmp_path / "m.toml").write_text(
        'methods = ["ls"]\ndiagnose = false\ncolumns = "map.toml"\n[[zone]]\nid = "[vav-3]"\ndata = "z.csv"\n'
        '[[zone]]\nid = "bad[/]zone"\ndata = "missing [degf].csv"\n'
    )
    rc = main(["fit-many", str(tmp_path / "m.toml"), "--backend", "processes", "--workers", "1"])
    out = capsys.readouterr().out
    assert rc == 4, out
    assert "failed bad[/]zone (ls): DataError: data file" in out and "missing [degf].csv" in out
