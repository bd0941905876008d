"""VDI 6007-1 test cases: rczone's networks against the guideline's and IBPSA's reference numbers.

The reference numbers are this folder's own copies (``data/``, with provenance and the IBPSA
licence notice), independent of the copies the package ships for ``rczone validate``.
"""

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from rczone.cli.main import main
from rczone.reference import vdi6007
from rczone.simulation import simulate

DATA = Path(__file__).parent / "data"


@pytest.fixture(scope="module", params=vdi6007.CASES)
def case(request):
    name = request.param
    n = name[2:]
    return (
        name,
        vdi6007.hourly_means(name),
        pd.read_csv(DATA / f"TestCase{n}_reference.csv"),
        pd.read_csv(DATA / f"TestCase{n}_dymola_regression_meany.csv"),
    )


def test_hourly_means_within_015_K_of_vdi_on_days_1_10_60(case):
    name, means, ref, _ = case
    checked = 0
    for day in (0, 9, 59):
        for h in range(1, 25):
            t = day * 86400.0 + h * 3600.0
            row = ref[np.isclose(ref["time_s"], t)]
            assert len(row), (name, t)
            assert abs(means[day * 24 + h - 1] - row["col2"].iloc[-1]) <= 0.15, (name, day + 1, h)
            checked += 1
    assert checked == 72


def test_hourly_means_within_001_K_of_ibpsa_dymola(case):
    name, means, _, dym = case
    t, y = dym["time_s"].to_numpy(), dym["mean_y"].to_numpy() - 273.15
    keep = (t > 3600) & (np.mod(t, 3600) != 0)  # on an hour boundary the sampled mean jumps
    assert keep.sum() >= 79
    dev = np.abs(means[(t[keep] // 3600).astype(int) - 1] - y[keep])
    assert dev.max() <= 0.01, name
    if name in ("TC1", "TC2", "TC3", "TC4", "TC5"):
        assert dev.max() <= 5e-4, name  # the same network and inputs as IBPSA's: agreement to rounding


def test_exact_hourly_means_equal_a_fine_simulation():
    """The hour-by-hour exact integration agrees with rczone.simulation at 10 s steps."""
    spec = vdi6007.SPECS["TC5"]
    ss = vdi6007.network(spec).state_space()
    u_day, _, _ = vdi6007.inputs("TC5")
    t = np.arange(0, 2 * 86400 + 1, 10.0)
    hour = (t // 3600).astype(int) % 24
    sim = simulate(ss, t, u_day[hour], x0=np.full(ss.n_states, 22.0), hold="zoh")
    # ZOH holds u[k] over [t_k, t_k+1): interval means of y by the trapezoid of the state part
    y = sim.y[:, 0]
    Cx = y - u_day[hour] @ ss.D[0]
    interval = 0.5 * (Cx[:-1] + Cx[1:]) + u_day[hour[:-1]] @ ss.D[0]
    fine = interval.reshape(48, 360).mean(axis=1)
    np.testing.assert_allclose(fine, vdi6007.hourly_means("TC5")[:48], atol=2e-4)


def test_cli_json_and_bad_case(tmp_path, capsys):
    out = tmp_path / "v.json"
    assert main(["validate", "vdi6007", "--case", "TC1", "--case", "TC12", "--json", str(out)]) == 0
    d = json.loads(out.read_text())
    assert set(d["cases"]) == {"TC1", "TC12"}
    assert d["cases"]["TC1"]["max_dev_vdi_K"] < 0.15 and d["cases"]["TC1"]["max_dev_dymola_K"] < 0.01
    assert d["cases"]["TC12"]["pass"] is True
    assert main(["validate", "vdi6007", "--case", "TC13"]) == 2
    err = capsys.readouterr().err
    assert "unknown VDI 6007 test case 'TC13'" in err and "Traceback" not in err
