"""`rczone fit --hold/--bounds/--fix/--free +NAME`: the API's fit settings on the command line (issue 22).

The data are the TiTe+heater zone simulated by scipy's ``lsim``, which interpolates the inputs
linearly between samples: a first-order hold, independent of rczone's discretization. On 30-min
samples of a heater switching every sample, only ``--hold foh`` describes them: it recovers the
R and C, while the default zero-order hold is biased.
"""

import json

import numpy as np
import pandas as pd
import pytest
from scipy import signal

from rczone.cli.main import main
from rczone.errors import ParameterError
from rczone.models import load_model
from rczone.workflow import FitSettings

TRUTH = {"Ci": 2e6, "Ce": 8e6, "Rie": 0.0025, "Rea": 0.006}
DT = 1800.0


def _zone() -> pd.DataFrame:
    ci, ce, rie, rea = (TRUTH[k] for k in ("Ci", "Ce", "Rie", "Rea"))
    a = [[-1 / (ci * rie), 1 / (ci * rie)], [1 / (ce * rie), -1 / (ce * rie) - 1 / (ce * rea)]]
    b = [[0.0, 1 / ci], [1 / (ce * rea), 0.0]]  # inputs To, Ph
    t = DT * np.arange(3 * 48 + 1)
    rng = np.random.default_rng(7)
    to = 3.0 + 4.0 * np.sin(2 * np.pi * t / 86400.0)
    ph = rng.choice([0.0, 3000.0], t.size)
    _, y, _ = signal.lsim((a, b, [[1.0, 0.0]], [[0.0, 0.0]]), np.column_stack([to, ph]), t, X0=[20.0, 12.0])
    return pd.DataFrame({"time": t, "To": to, "Ph": ph, "Ti": y})


@pytest.fixture(scope="module")
def zone(tmp_path_factory):
    path = tmp_path_factory.mktemp("opts") / "zone.csv"
    _zone().to_csv(path, index=False)
    return path


def _fit(zone, *extra):
    out = zone.parent / "fit.json"
    args = ["fit", str(zone), "--model", "TiTe+heater", "--method", "ls", "--starts", "1", "--no-profiles"]
    rc = main([*args, "--json", str(out), *extra])
    return rc, json.loads(out.read_text())


def _worst(d) -> float:
    return max(abs(d["parameters"][k]["estimate"] / v - 1) for k, v in TRUTH.items() if k in d["parameters"])


def test_foh_recovers_data_made_with_linear_inputs_and_zoh_does_not(zone):
    _, foh = _fit(zone, "--hold", "foh")
    _, zoh = _fit(zone)
    assert _worst(foh) < 0.01
    assert _worst(zoh) > 0.05
    assert foh["hold"] == "foh" and zoh["hold"] == "zoh"


def test_fix_holds_a_parameter_at_the_value_given(zone, capsys):
    _, d = _fit(zone, "--hold", "foh", "--fix", "Rea=0.006")
    assert "Rea" not in d["parameters"] and d["fixed"]["Rea"] == 0.006
    assert _worst(d) < 0.01
    assert capsys.readouterr().out.count("open-loop RMSE") == 1  # an LS fit's RMSE is said once


def test_a_model_files_unit_after_the_numbers_is_converted_to_si(zone):
    _, d = _fit(zone, "--hold", "foh", "--fix", "Rea=6 K/kW", "--bounds", "Ci=0.1,1 kWh/K")
    assert d["fixed"]["Rea"] == pytest.approx(0.006, rel=1e-12)
    ci = d["parameters"]["Ci"]
    assert (ci["lower"], ci["upper"]) == pytest.approx((3.6e5, 3.6e6), rel=1e-12)  # 1 kWh = 3.6 MJ
    assert _worst(d) < 0.01


def test_bounds_replace_the_declared_ones_and_a_bound_that_excludes_the_truth_is_flagged(zone):
    rc, d = _fit(zone, "--hold", "foh", "--bounds", "Ci=1e5,1.5e6")
    ci = d["parameters"]["Ci"]
    assert (ci["lower"], ci["upper"]) == (1e5, 1.5e6)
    assert rc == 3 and ci["at_bound"] and ci["estimate"] == pytest.approx(1.5e6, rel=1e-3)


def test_noise_levels_are_fixed_and_freed_by_name(zone):
    out = zone.parent / "ml.json"
    args = ["fit", str(zone), "--model", "TiTe+heater", "--starts", "1", "--no-profiles", "--hold", "foh"]
    rc = main([*args, "--fix", "sigma_v=0.02", "--free", "+sigma_w_Te", "--json", str(out)])
    d = json.loads(out.read_text())
    assert rc in (0, 3)
    assert "sigma_w_Te" in d["parameters"] and "sigma_w_Ti" in d["parameters"]
    assert "sigma_v" not in d["parameters"] and d["fixed"]["sigma_v"] == 0.02


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--bounds", "Ci=5e6,1e6"], "lower 5e+06 must be < upper 1e+06"),
        (["--bounds", "Cii=1e5,1e7"], "did you mean 'Ci'"),
        (["--bounds", "Ci=2e6,5e6"], "start of 'Ci' = 1e+06 is outside its bounds"),
        (["--bounds", "Ci=1e5"], "--bounds must be NAME=LO,HI"),
        (["--fix", "sigma_wTi=0.1"], "did you mean 'sigma_w_Ti'"),
        (["--fix", "Rea=cold"], "--fix must be NAME or NAME=VALUE"),
        (["--fix", "Rea", "--free", "Rea,Ci"], "'Rea' is both free and fixed"),
        (["--hold", "cubic"], "hold must be one of zoh, foh"),
        (["--bounds", "Ci=1,2 K/kW"], "'K/kW' is not a unit of a capacitance"),
        (["--fix", "sigma_v=1 mK"], "a unit is for a resistance, capacity or gain"),
        (["--bounds", "x0_Ti=10,30"], "which this fit does not estimate; free it too (--free +x0_Ti"),
    ],
)
def test_mistakes_in_the_options_exit_2_with_one_line(zone, capsys, extra, message):
    args = ["fit", str(zone), "--model", "TiTe+heater", "--method", "ls", "--starts", "1", *extra]
    rc = main(args)
    err = capsys.readouterr().err
    assert rc == 2 and message in err and "Traceback" not in err
    assert len([ln for ln in err.splitlines() if ln.startswith("error:")]) == 1


def test_the_settings_resolve_the_free_set_as_the_command_line_does():
    net = load_model("TiTe+heater").network
    s = FitSettings(free=("+sigma_w_Te", "+x0_Te"), fixed={"Rea": None, "sigma_v": 0.02})
    assert s.free_for(net) == ("Ci", "Ce", "Rie", "sigma_w_Ti", "sigma_w_Te", "x0_Te")
    assert FitSettings(free=("Ci", "+Rea")).free_for(net) == ("Ci", "Rea")
    with pytest.raises(ParameterError, match="every parameter is fixed"):
        FitSettings(method="ls", fixed=dict.fromkeys(("Ci", "Ce", "Rie", "Rea", "x0_Te"))).free_for(net)


def test_select_refuses_a_bound_no_candidate_estimates(zone, capsys):
    args = ["select", str(zone), "--model", "Ti+heater", "--model", "TiTe+heater", "--bounds", "Cx=1e5,1e7"]
    rc = main(args)
    err = capsys.readouterr().err
    assert rc == 2 and "bounds given for 'Cx', which no candidate estimates; did you mean" in err
