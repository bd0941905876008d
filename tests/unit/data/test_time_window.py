"""``[time] start`` and ``end`` of a column map: only a window of a long trend log, in local time."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from rczone.data import load_zone_data
from rczone.errors import DataError


def _log(tmp_path):
    stamps = pd.date_range("2014-07-01 00:00", periods=96, freq="h")  # local, naive
    df = pd.DataFrame({"Timestamp": stamps.strftime("%Y-%m-%d %H:%M"), "T": 20 + np.sin(np.arange(96) / 5)})
    df.to_csv(tmp_path / "log.csv", index=False)
    return tmp_path / "log.csv"


def _map(tmp_path, extra: str) -> str:
    text = f'[time]\ncolumn = "Timestamp"\ntimezone = "America/Los_Angeles"\n{extra}\n[columns]\nTi = "T"\n'
    (tmp_path / "map.toml").write_text(text)
    return str(tmp_path / "map.toml")


@pytest.mark.parametrize("start", ['"2014-07-02"', "2014-07-02", '"2014-07-02 00:00"'])
def test_the_window_is_local_and_half_open(tmp_path, start) -> None:
    zd = load_zone_data(_log(tmp_path), _map(tmp_path, f'start = {start}\nend = "2014-07-03"'))
    local = pd.to_datetime(zd.t, unit="s", utc=True).tz_convert("America/Los_Angeles")
    assert local[0] == pd.Timestamp("2014-07-02 00:00", tz="America/Los_Angeles")
    assert local[-1] == pd.Timestamp("2014-07-02 23:00", tz="America/Los_Angeles") and zd.t.size == 24


def test_only_a_start_or_only_an_end(tmp_path) -> None:
    assert load_zone_data(_log(tmp_path), _map(tmp_path, 'start = "2014-07-04"')).t.size == 24
    assert load_zone_data(_log(tmp_path), _map(tmp_path, 'end = "2014-07-01 12:00"')).t.size == 12


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        ('start = "2014-07-03"\nend = "2014-07-02"', "start must be before end"),
        ('start = "soon"', "is not a date"),
        (
            'start = "2015-01-01"',
            r"no rows between .* the data run from 2014-07-01 00:00 to 2014-07-04 23:00",
        ),
    ],
)
def test_bad_windows_are_one_line(tmp_path, extra, match) -> None:
    with pytest.raises(DataError, match=match):
        load_zone_data(_log(tmp_path), _map(tmp_path, extra))
