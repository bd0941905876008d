"""Joint identification of two coupled rooms vs one room with the neighbour's measured temperature as input."""

import json

import numpy as np
import pytest
from scipy.stats import multivariate_normal, norm
from statsmodels.stats.sandwich_covariance import S_hac_simple

from rczone.cli.main import main
from rczone.errors import ParameterError
from rczone.estimation.data import Dataset
from rczone.estimation.engines import run_filter
from rczone.models import load_model
from rczone.selection import select_models
from rczone.selection.coupling import (
    Basis,
    comparison_basis,
    conditional_loglik,
    conditional_terms,
    newey_west_variance,
    vuong_test,
)
from tests.unit.selection import coupled

N, DT = 600, 600.0
NOISY = (0.02, 0.3)  # the neighbour's sensor is poor: using it as an input is an errors-in-variables model


@pytest.fixture(scope="module")
def paths(tmp_path_factory):
    d = tmp_path_factory.mktemp("coupled")
    out = coupled.write_models(d)
    coupled.joint_data(N, DT, NOISY, 3).to_csv(d / "noisy.csv", index=False)
    coupled.controlled_neighbour_data(N, DT, 4).to_csv(d / "controlled.csv", index=False)
    out["noisy"], out["controlled"] = str(d / "noisy.csv"), str(d / "controlled.csv")
    return out


# ----------------------------------------------------------------------------- Gaussian conditioning
def test_conditional_terms_equal_scipy_conditional_densities_with_missing_values():
    rng = np.random.default_rng(0)
    n, ny = 40, 3
    L = rng.normal(size=(n, ny, ny))
    S = L @ L.transpose(0, 2, 1) + 0.1 * np.eye(ny)
    e = np.array([rng.multivariate_normal(np.zeros(ny), s) for s in S])
    e[3, 2] = np.nan  # a neighbour missing: not conditioned on
    e[5, 0] = np.nan  # the target missing: contributes nothing
    e[7, [0, 1]] = np.nan
    got = conditional_terms(e, S, [0], [1, 2])
    for k in range(n):
        ok = [j for j in (1, 2) if np.isfinite(e[k, j])]
        if not np.isfinite(e[k, 0]):
            assert got[k] == 0.0
            continue
        # the conditional law written out: mean S12 S22^-1 e2, covariance S11 - S12 S22^-1 S21
        s11, s12, s22 = S[k, 0, 0], S[k, 0, ok], S[k][np.ix_(ok, ok)]
        mean = s12 @ np.linalg.solve(s22, e[k, ok]) if ok else 0.0
        var = s11 - (s12 @ np.linalg.solve(s22, s12) if ok else 0.0)
        assert got[k] == pytest.approx(norm(mean, np.sqrt(var)).logpdf(e[k, 0]), rel=1e-10)
    # two targets: the joint minus the marginal, by scipy
    both = conditional_terms(e[:3], S[:3], [0, 1], [2])
    for k in range(3):
        ref = multivariate_normal(np.zeros(3), S[k]).logpdf(e[k]) - norm(0, np.sqrt(S[k, 2, 2])).logpdf(
            e[k, 2]
        )
        assert both[k] == pytest.approx(ref, rel=1e-10)


@pytest.mark.parametrize(("targets", "given", "match"), [([], [1], "non-empty"), ([0], [0], "disjoint")])
def test_conditional_terms_bad_indices(targets, given, match):
    with pytest.raises(ParameterError, match=match):
        conditional_terms(np.zeros((2, 2)), np.tile(np.eye(2), (2, 1, 1)), targets, given)


def test_newey_west_variance_equals_statsmodels_hac():
    rng = np.random.default_rng(1)
    d = np.convolve(rng.normal(size=500), [1.0, 0.6, 0.3], mode="same") + 0.2
    x = d - d.mean()
    for lags in (0, 3, 7):
        assert newey_west_variance(d, lags) == pytest.approx(S_hac_simple(x, nlags=lags)[0, 0] / d.size)
    assert newey_west_variance(d) == pytest.approx(S_hac_simple(x)[0, 0] / d.size)


def test_vuong_statistic_and_p_value():
    rng = np.random.default_rng(2)
    la, lb = rng.normal(0.1, 1, 400), rng.normal(0, 1, 400)
    v = vuong_test("a", "b", la, lb, 3, 1)
    d = la - lb
    z = d.sum() / np.sqrt(d.size * newey_west_variance(d))
    assert v.statistic == pytest.approx(z) and v.p_value == pytest.approx(2 * norm.sf(abs(z)))
    assert v.statistic_bic == pytest.approx(
        (d.sum() - np.log(400)) / np.sqrt(d.size * newey_west_variance(d))
    )
    same = vuong_test("a", "b", la, la, 3, 1)
    assert same.statistic == 0 and same.closer(0.05) is None
    with pytest.raises(ParameterError, match="at least 10"):
        vuong_test("a", "b", la[:5], lb[:5], 1, 1)


# ----------------------------------------------------------------------------- the basis
def test_comparison_basis(paths):
    nets = {k: load_model(paths[k]).network for k in ("joint", "single", "alone")}
    assert comparison_basis({"j": nets["joint"], "s": nets["single"]}) == Basis(("T1",), ("T2",))
    assert comparison_basis({"s": nets["single"], "a": nets["alone"]}) == Basis(("T1",))
    with pytest.raises(ParameterError, match="'a' neither measures 'T2' nor takes it as a boundary"):
        comparison_basis({"j": nets["joint"], "s": nets["single"], "a": nets["alone"]})
    other = load_model("Ti+heater").network
    with pytest.raises(ParameterError, match="no output in common"):
        comparison_basis({"j": nets["joint"], "o": other})


# ----------------------------------------------------------------------------- against a plain filter
def test_joint_conditional_loglik_at_the_truth_equals_a_textbook_filter(paths):
    frame = coupled.joint_data(200, DT, NOISY, 5)
    zm = load_model(paths["joint"])
    net = zm.network
    data = Dataset(
        frame["time"].to_numpy(),
        frame[list(net.input_names)].to_numpy(),
        None,
        frame[["T1", "T2"]].to_numpy(),
        net.input_names,
        (),
        net.outputs,
    )
    y0 = data.y[0]
    values = {
        **coupled.TRUE,
        "sigma_w_T1": coupled.SIGMA_W["T1"],
        "sigma_w_T2": coupled.SIGMA_W["T2"],
        "sigma_v_T1": NOISY[0],
        "sigma_v_T2": NOISY[1],
        "x0_T1": y0[0],
        "x0_T2": y0[1],
        "sigma_x0_T1": 0.5,
        "sigma_x0_T2": 0.5,
    }
    got = conditional_loglik(net, values, data, Basis(("T1",), ("T2",)))
    ref = coupled.reference_conditional(frame, NOISY, 0.5)
    np.testing.assert_allclose(got, ref, rtol=1e-7, atol=1e-9)
    # without conditioning outputs the terms are the filter's own likelihood
    joint = conditional_loglik(net, values, data, Basis(("T1", "T2")))
    assert joint.sum() == pytest.approx(-run_filter(net, values, data).nll, rel=1e-10)
    with pytest.raises(ParameterError, match="measures T1, T2"):
        conditional_loglik(net, values, data, Basis(("T1",)))


# ----------------------------------------------------------------------------- choosing
@pytest.mark.parametrize(("case", "right"), [("noisy", "joint"), ("controlled", "single")])
def test_the_comparison_picks_the_right_model(paths, case, right):
    import pandas as pd

    sel = select_models([paths["joint"], paths["single"]], pd.read_csv(paths[case]), n_starts=1)
    names = {k: n for n in sel.candidates for k in ("joint", "single") if n.startswith(k)}
    assert sel.basis == Basis(("T1",), ("T2",)) and sel.selected == names[right]
    (v,) = sel.vuong
    terms = {n: c.terms for n, c in sel.candidates.items()}
    assert v.loglik_ratio == pytest.approx(terms[v.a].sum() - terms[v.b].sum())
    # the joint model's raw likelihood (of T1 and T2) is not what is compared
    joint = sel.candidates[names["joint"]]
    assert joint.loglik != pytest.approx(joint.fit_loglik, abs=1.0)
    if right == "joint":
        assert v.closer(0.05) == names["joint"]
    else:
        assert v.closer(0.05) in (None, names["single"])
        # the neighbour-input model is the truth: its conditional likelihood is its own
        single = sel.candidates[names["single"]]
        assert single.loglik == pytest.approx(single.fit_loglik, rel=1e-9)


# ----------------------------------------------------------------------------- the CLI
def test_select_cli_reports_the_basis_and_vuong(paths, capsys, tmp_path):
    args = ["select", paths["noisy"], "--model", paths["joint"], "--model", paths["single"], "--starts", "1"]
    assert main([*args, "--json", "-", "--report", str(tmp_path / "rep")]) == 0
    page = (tmp_path / "rep" / "report.html").read_text()
    assert "Vuong tests between non-nested candidates" in page and "conditional on T2" in page
    res = json.loads(capsys.readouterr().out)
    assert res["basis"] == "conditional on T2" and res["targets"] == ["T1"]
    (v,) = [t for t in res["tests"] if t["kind"] == "vuong"]
    assert v["closer"] == res["selected"] and v["p_value"] < 1e-3
    assert res["samples"]["n_obs"] == N


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--model", "alone"], "neither measures 'T2' nor takes it as a boundary"),
        (["--forward"], "forward selection moves between nested models"),
        (["--const", "T2=20"], "cannot hold 'T2' constant: it is a node or output"),
    ],
)
def test_select_cli_refuses_incomparable_candidates_with_one_line(paths, capsys, extra, message):
    models = ["--model", paths["joint"], "--model", paths["single"]]
    extra = ["--model", paths["alone"]] if extra[-1] == "alone" else extra
    rc = main(["select", paths["noisy"], *models, *extra])
    err = capsys.readouterr().err
    assert rc == 2 and message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
