"""`rczone demo` end to end: the files it promises, and the paper's findings on the virtual building."""

import json
import re

import numpy as np
import pytest

from rczone.cli.main import main
from rczone.models import get_model

pytestmark = pytest.mark.slow  # > 4 s: out of make test (2026-12-02 durations), run by pytest -m slow

ORDERS = ("full-scale", "second-order", "first-order")


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    assert main(["demo", "--out", str(out)]) == 0
    return out, json.loads((out / "results.json").read_text())


def test_writes_report_figures_and_results(demo):
    out, _ = demo
    html = (out / "report.html").read_text()
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert {"fig4_time_domain.png", "fig5_gains.png", "fig6_errors.png"} <= set(pngs)
    # every figure is embedded, so the report is self-contained
    assert len(re.findall(r'<img [^>]*src="data:image/png;base64,', html)) >= len(pngs)
    assert "IV. Can R and C be identified" in html


def test_results_hold_time_and_frequency_errors_per_scenario_and_order(demo):
    _, res = demo
    td = res["model_order"]["time_domain"]
    for s in "ABC":
        for k in ORDERS:
            assert td[s][k]["rmse_K"] > 0 and td[s][k]["max_error_K"] >= td[s][k]["rmse_K"]
        assert td[s]["full-scale"]["max_diff_to_full_scale_K"] == 0.0
    fd = res["model_order"]["frequency_domain"]
    for k in ("second-order", "first-order"):
        assert set(fd["max_error_K"][k]) == {"Ts", "Tsd", "To"}
        # e_i is proportional to du_i: the per-night tables scale with each night's variation
        for s in "ABC":
            du_all, du_s = fd["du_K"]["Ts"], fd["per_data_set"][s]["du_K"]["Ts"]
            assert fd["per_data_set"][s]["max_error_K"][k]["Ts"] == pytest.approx(
                fd["max_error_K"][k]["Ts"] * du_s / du_all, rel=1e-9
            )
    # the 1st-order model is the worse approximation of the full-scale model, in both domains
    assert max(fd["max_error_K"]["first-order"].values()) > max(fd["max_error_K"]["second-order"].values())
    assert (
        td["C"]["first-order"]["max_diff_to_full_scale_K"]
        > td["C"]["second-order"]["max_diff_to_full_scale_K"]
    )


def test_identification_reproduces_the_papers_lesson(demo):
    _, res = demo
    ident = res["identification"]
    construction = get_model("second-order-paper").values()["Rw"]
    # diagnose, before any fit: closed-loop nights cannot identify Rw, the forced test can
    verdicts = {s: ident["diagnose"][s]["Rw"]["verdict"] for s in "ABC"}
    assert verdicts == {"A": "not identifiable", "B": "not identifiable", "C": "identifiable"}
    a, c = ident["attempts"]["1"]["methods"], ident["attempts"]["2"]["methods"]
    # the fit to closed-loop night A matches A, but its Rw is grossly wrong and it fails on C
    assert a["ls"]["parameters"]["Rw"]["estimate"] < 0.3 * construction
    assert a["ls"]["validation"]["A"]["rmse_K"] < 0.15
    assert a["ls"]["validation"]["C"]["rmse_K"] > 2 * c["ls"]["validation"]["C"]["rmse_K"]
    # the fit to the forced night C carries over to the closed-loop nights
    for s in "AB":
        assert c["ls"]["validation"][s]["rmse_K"] < 0.25


def test_map_on_closed_loop_data_stays_near_construction_and_predicts_the_forced_night(demo):
    _, res = demo
    a = res["identification"]["attempts"]["1"]["methods"]
    rw = {m: a[m]["parameters"]["Rw"] for m in ("ls", "ml", "map")}
    construction = rw["map"]["construction"]
    assert abs(np.log(rw["map"]["estimate"] / construction)) < abs(
        np.log(rw["ml"]["estimate"] / construction)
    )
    # it admits what it does not know
    assert rw["map"]["std_error"] / rw["map"]["estimate"] > 3 * rw["ls"]["std_error"] / rw["ls"]["estimate"]
    assert a["map"]["validation"]["C"]["rmse_K"] < a["ls"]["validation"]["C"]["rmse_K"]


def test_band_matched_second_order_meets_the_papers_1F_at_its_weights(demo):
    pw = demo[1]["model_order"]["frequency_domain"]["paper_weights"]
    assert pw["du_F"] == pytest.approx({"Ts": 45.0, "Tsd": 10.0, "To": 45.0})
    assert pw["agrees_with_paper"]["second-order-band"] is True
    assert pw["agrees_with_paper"]["second-order"] is False  # the parallel aggregation does not
    assert max(pw["max_error_F"]["second-order-band"].values()) <= 1.0
    # the band values keep the steady state: same window and total wall resistance
    par, band = pw["values"]["second-order"], pw["values"]["second-order-band"]
    assert band["Rwin"] == pytest.approx(par["Rwin"])
    assert band["R1"] + band["R2"] == pytest.approx(par["R1"] + par["R2"])


def test_closed_loop_case_at_the_papers_strength(demo):
    cl = demo[1]["closed_loop"]
    ls = cl["thermostat at the diffuser"]["ls"]
    assert cl["thermostat at the diffuser"]["paper_strength"] is True
    assert ls["rw_ratio_C_over_A"] >= 5.0 and ls["A"]["own_rmse_K"] <= 0.2
    assert cl["as shipped"]["ls"]["rw_ratio_C_over_A"] < 5.0
    # the wrong model fails on the forced night of its own building
    assert ls["A"]["C_rmse_K"] > 2 * ls["C"]["own_rmse_K"]
    mp = demo[1]["identification"]["map_prior"]
    assert mp["better"] in ("parallel", "band") and set(mp["rules"]) == {"parallel", "band"}


def test_the_report_opens_with_a_summary_of_computed_findings_and_parameters_with_units(demo):
    out, res = demo
    html = (out / "report.html").read_text()
    headings = re.findall(r"<h2>(.*?)</h2>", html)
    assert headings[0] == "Summary" and headings.index("Summary") < headings.index(
        "III. Which model order is enough?"
    )
    summary = html[html.index("<h2>Summary</h2>") : html.index("<h2>III.")]
    # the numbers are the results', not prose: the closed-loop fit's Rw and its error on C
    a = res["identification"]["attempts"]["1"]["methods"]["ls"]
    assert f"Rw = {a['parameters']['Rw']['estimate']:.3g} K/W" in summary
    assert f"({a['validation']['C']['rmse_K']:.2f} K)" in summary
    for s in "ABC":
        assert f"{res['identification']['diagnose'][s]['Rw']['verdict']}</b> on {s}" in summary
    # the parameter table: one row per parameter with its unit, a column per fit
    assert "<th>unit</th>" in summary and "<td>K/W</td>" in summary and "<td>J/K</td>" in summary
    assert "<th>LS on A</th>" in summary and "<th>ML on C</th>" in summary
