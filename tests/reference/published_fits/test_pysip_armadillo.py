"""External oracle: pySIP's published maximum-likelihood fit on the Armadillo data (see README.md)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rczone.estimation import Dataset, fit, ml_cost
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor
from tests.shared_data import SHARED, require

REF_FILE = SHARED / "reference" / "published_fits.json"
DATA_FILE = SHARED / "data" / "armadillo_pysip" / "armadillo_data_H2.csv"


@pytest.fixture(autouse=True)
def _armadillo_files() -> None:
    require(REF_FILE, DATA_FILE, what="shared Armadillo data/reference")


DAY = 86400.0  # pySIP's time unit in this example is the day

# pySIP's TwTi_RoRi: wall node Tw (Cw) to outdoor To through Ro, room node Ti (Ci) through Ri, heat on Ti
NET = RCNetwork(
    "TwTi_RoRi",
    nodes=[Node("Tw", "Cw"), Node("Ti", "Ci")],
    boundaries=["To"],
    resistors=[Resistor("Tw", "To", "Ro"), Resistor("Tw", "Ti", "Ri")],
    heat_inputs=[HeatInput("Qh", {"Ti": 1.0})],
    parameters=[
        Parameter("Ro", "resistance", 0.01),
        Parameter("Ri", "resistance", 0.01),
        Parameter("Cw", "capacitance", 1e7),
        Parameter("Ci", "capacitance", 1e6),
    ],
    outputs=["Ti"],
)


def load():
    import pandas as pd

    ref = json.loads(REF_FILE.read_text())["pysip_armadillo_TwTi_RoRi"]
    df = pd.read_csv(DATA_FILE).iloc[:-1]  # pySIP drops the last row: 232 samples
    df = df.rename(columns={"T_ext": "To", "P_hea": "Qh", "T_int": "Ti"}).set_index("Time")
    data = Dataset.from_frame(df, NET)
    return ref, data


def to_si(p: dict[str, float]) -> dict[str, float]:
    """pySIP (days) -> rczone (SI seconds) names and units."""
    return {
        "Ro": p["Ro"],
        "Ri": p["Ri"],
        "Cw": p["Cw"] * DAY,
        "Ci": p["Ci"] * DAY,
        "sigma_w_Tw": p["sigw_w"] / np.sqrt(DAY),
        "sigma_v": p["sigv"],
        "x0_Tw": p["x0_w"],
    }


def fixed_si(ref) -> dict[str, float]:
    f = ref["fixed"]
    return {
        "sigma_w_Ti": f["sigw_i"],
        "x0_Ti": f["x0_i"],
        "sigma_x0_Tw": f["sigx0_w"],
        "sigma_x0_Ti": f["sigx0_i"],
    }


def test_published_negative_log_likelihood() -> None:
    ref, data = load()
    assert data.n_samples == 232
    values = {**to_si(ref["estimate"]), **fixed_si(ref)}
    nll = ml_cost(NET, values, data, hold="foh")
    assert nll == pytest.approx(ref["negative_log_likelihood_incl_0.5nlog2pi"], abs=1e-4)


def test_refit_from_start_two_times_off_reaches_published_estimates() -> None:
    ref, data = load()
    est = to_si(ref["estimate"])
    start = {k: (v + 1.0 if k == "x0_Tw" else 2.0 * v) for k, v in est.items()}
    bounds = {k: (v / 100, v * 100) for k, v in est.items() if k != "x0_Tw"}
    res = fit(
        NET,
        data,
        free=list(est),
        method="ml",
        optimizer="lbfgs",
        start=start,
        bounds=bounds,
        fixed=fixed_si(ref),
        hold="foh",
    )
    assert res.converged
    for k, v in est.items():
        assert res.estimates[k] == pytest.approx(v, rel=1e-3), k
    assert -res.llf == pytest.approx(ref["negative_log_likelihood_incl_0.5nlog2pi"], abs=1e-4)
    se = to_si({**ref["std_errors"]})
    for k, v in se.items():
        assert res.std_errors[k] == pytest.approx(v, rel=0.10), k
    assert not any(e.at_bound for e in res.parameters.values())
