"""The k-step method as a plug-in: its options, the API and the command line."""

from __future__ import annotations

import json

import pytest

from rczone.cli.main import main
from rczone.errors import ParameterError
from rczone.estimation.methods.kstep import KStepOptions
from rczone.estimation.methods.registry import method_of
from tests.unit.calibration.test_drift import MODEL, virtual_zone


def test_the_method_is_registered_with_its_horizons_option():
    m = method_of("kstep")
    assert m.options is KStepOptions and m.stochastic and m.kernel == "ml"
    assert KStepOptions.parse(["horizons=12,1,72"], "kstep").horizons == (1, 12, 72)
    assert KStepOptions().horizons == (1, 12, 72)


@pytest.mark.parametrize("bad", [["horizons=0,12"], ["horizons=x"], ["horizon=1"]])
def test_bad_options_are_one_line_errors(bad):
    with pytest.raises(ParameterError, match="horizon"):
        KStepOptions.parse(bad, "kstep")


@pytest.mark.slow
def test_fit_method_kstep_from_the_command_line_and_the_api(tmp_path, capsys):
    import rczone

    (tmp_path / "zone.toml").write_text(MODEL)
    frame = virtual_zone(7, days=2.0)
    frame.to_csv(tmp_path / "zone.csv", index=False)
    out = tmp_path / "fit.json"
    args = ["fit", str(tmp_path / "zone.csv"), "--model", str(tmp_path / "zone.toml"), "--method", "kstep"]
    assert main([*args, "--option", "horizons=1,12", "--starts", "1", "--json", str(out)]) == 0
    res = json.loads(out.read_text())
    assert res["method"] == "kstep"
    cal = rczone.fit(tmp_path / "zone.toml", frame, method="kstep", options={"horizons": (1, 12)}, n_starts=1)
    r = cal.result
    assert r.method == "kstep" and any("k-step criterion" in n for n in r.notes)
    assert all(e.std_error > 0 for n, e in r.parameters.items() if n in ("Ci", "Ce", "Rie", "Rea"))
    assert main([*args, "--option", "horizons=0"]) == 2
