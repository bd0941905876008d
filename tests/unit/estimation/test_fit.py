from __future__ import annotations

import json

import numpy as np
import pytest

from rczone.errors import InputShapeError, ParameterError
from rczone.estimation import Dataset, FitResult, fit

from .nets import NET1, NET2, data1, data2


def test_fit_result_to_dict_is_json_ready_and_complete() -> None:
    data = data2(noise=0.02, rng=np.random.default_rng(0))
    tiny_process_noise = {"sigma_w_Ti": 1e-6, "sigma_w_Tw": 1e-6}
    res = fit(
        NET2,
        data,
        ["Cr", "Rw", "sigma_v"],
        method="ml",
        optimizer="lbfgs",
        start={"Rw": 0.02},
        fixed=tiny_process_noise,
    )
    assert isinstance(res, FitResult)
    d = json.loads(json.dumps(res.to_dict()))
    p = d["parameters"]["Rw"]
    assert set(p) == {
        "estimate",
        "std_error",
        "construction",
        "lower",
        "upper",
        "ratio_to_construction",
        "at_bound",
        "unit",
        "interval_95",
    }
    assert p["construction"] == 0.01 and p["ratio_to_construction"] == pytest.approx(p["estimate"] / 0.01)
    assert p["std_error"] > 0 and p["at_bound"] is False
    assert d["parameters"]["sigma_v"]["construction"] is None  # noise has no construction value
    assert d["method"] == "ml" and d["rmse_kind"] == "one-step" and d["converged"] is True
    # the noise std estimate is close to the truth (0.02 K) and so is the one-step RMSE
    assert res.estimates["sigma_v"] == pytest.approx(0.02, rel=0.2)
    assert res.rmse_K == pytest.approx(0.02, rel=0.2)
    assert d["correlation"]["Cr"]["Cr"] == pytest.approx(1.0)


def test_multistart_keeps_every_start_and_reports_the_winner() -> None:
    data = data1()
    res = fit(
        NET1, data, ["Cr", "R"], method="ls", n_starts=4, rng=np.random.default_rng(42), uncertainty=False
    )
    assert len(res.starts) == 4 and res.search.n_local == 4 and res.search.strategy == "global"
    assert res.n_evals == res.search.n_sampled + sum(s.n_evals for s in res.starts)
    costs = [s.cost for s in res.starts]
    assert res.objective_value == min(costs) == costs[res.best_start]
    np.testing.assert_allclose(res.starts[0].start, [1e6, 0.01])  # first start: construction values
    rows = res.starts_table()
    assert sum(r["winner"] for r in rows) == 1 and "end_Cr" in rows[0]
    assert res.estimates["Cr"] == pytest.approx(1e6, rel=1e-4)
    # this problem is convex: a start either reaches its one optimum or was given up unconverged
    # after a stage of Gauss-Newton passes still above it (estimation.leastsq.staged); two agree
    for s in res.starts:
        assert not s.converged or np.allclose(s.end, [1e6, 0.01], rtol=1e-4)
    assert res.search.n_best >= 2 and res.converged and res.trustworthy


def test_fit_does_not_mutate_the_network() -> None:
    before = {k: (p.value, p.expr) for k, p in NET1.parameters.items()}
    fit(NET1, data1(), ["Cr", "R"], method="ls", start={"Cr": 3e6}, uncertainty=False)
    assert {k: (p.value, p.expr) for k, p in NET1.parameters.items()} == before


def test_estimate_at_a_bound_is_flagged() -> None:
    # truth R = 0.01 lies above the upper bound: the estimate must stop at the bound and say so
    res = fit(
        NET1,
        data1(),
        ["Cr", "R"],
        method="ls",
        bounds={"R": (1e-3, 5e-3)},
        start={"R": 2e-3},
        optimizer="lbfgs",
        uncertainty=False,
    )
    assert res.parameters["R"].at_bound and not res.parameters["Cr"].at_bound
    assert any("R is at a bound" in f for f in res.flags)
    # on the bound but strictly inside it (1e-9 of the range in eta), so the estimate can start a later fit
    assert res.estimates["R"] == pytest.approx(5e-3, rel=1e-8) and res.estimates["R"] < 5e-3


@pytest.mark.parametrize(
    ("kwargs", "err", "match"),
    [
        ({"free": ["Cx"]}, ParameterError, r"unknown free parameter 'Cx'; did you mean .*'Cr'"),
        ({"method": "ols"}, ParameterError, "method must be one of"),
        ({"optimizer": "bfgs"}, ParameterError, "optimizer must be 'auto' or one of"),
        ({"n_starts": 0}, ParameterError, "n_starts must be None .automatic. or an integer from 1"),
        ({"initial_state": "rest"}, ParameterError, "initial_state must be"),
        ({"hold": "linear"}, ParameterError, "hold must be one of"),
        ({"free": ["Cr", "sigma_v"]}, ParameterError, "cannot be estimated by least squares"),
        ({"bounds": {"Cr": (2e6, 1e6)}}, ParameterError, "must be < upper"),
        ({"bounds": {"Cr": (2e6, 3e6)}}, ParameterError, "outside its bounds"),
        ({"data": "data1"}, InputShapeError, "do not match network"),
        ({"data": np.zeros((3, 3))}, ParameterError, "must be an rczone Dataset"),
    ],
)
def test_bad_fit_inputs_raise(kwargs, err, match) -> None:
    args = {"network": NET2, "data": data2(n=20), "free": ["Cr", "Rw"], "method": "ls", **kwargs}
    if isinstance(args["data"], str):
        args["data"] = data1(n=20)
    with pytest.raises(err, match=match):
        fit(**args)


def test_data_shape_mismatch_with_network_is_reported() -> None:
    d = data2(n=20)
    short = Dataset(d.t, d.u[:, :3], d.m, d.y, d.input_names[:3], d.flow_names, d.output_names)
    with pytest.raises(InputShapeError, match=r"data inputs \['To', 'Tsd', 'Ts'\] do not match"):
        fit(NET2, short, ["Cr"], method="ls")


def test_map_prior_pulls_towards_construction_by_its_spread() -> None:
    # data from Rw = 0.02 while the network declares (construction) Rw = 0.01
    from rczone.network import Parameter
    from rczone.simulation import simulate

    d = data2()
    truth = NET2.replace_parameters([Parameter("Rw", "resistance", 0.02)])
    y = simulate(truth.state_space(), d.t, d.u, d.m).y + 0.02 * np.random.default_rng(4).standard_normal(
        d.y.shape
    )
    data = Dataset(d.t, d.u, d.m, y, d.input_names, d.flow_names, d.output_names)
    kw = {"optimizer": "lbfgs", "uncertainty": False, "fixed": {"sigma_v": 0.02}}
    ml = fit(NET2, data, ["Rw"], method="ml", **kw).estimates["Rw"]
    tight = fit(NET2, data, ["Rw"], method="map", options={"prior_spread": 1e-4}, **kw).estimates["Rw"]
    loose = fit(NET2, data, ["Rw"], method="map", **kw).estimates["Rw"]
    assert ml == pytest.approx(0.02, rel=0.03)
    assert tight == pytest.approx(0.01, rel=1e-3)
    assert 0.01 < loose < ml


@pytest.mark.parametrize("correlation_time", [600.0, 18000.0])
def test_map_mode_is_the_precision_weighted_mean_of_tempered_likelihood_and_prior(correlation_time) -> None:
    """For a near-Gaussian likelihood in log Rw, the MAP mode is Bayes' rule with the likelihood's
    precision scaled by w = dt / t_corr (1 when t_corr equals the sample time)."""
    from rczone.estimation.costs import PRIOR_SPREAD
    from rczone.network import Parameter
    from rczone.simulation import simulate

    d = data2()
    truth = NET2.replace_parameters([Parameter("Rw", "resistance", 0.02)])
    rng = np.random.default_rng(5)
    y = simulate(truth.state_space(), d.t, d.u, d.m).y + 1.0 * rng.standard_normal(d.y.shape)
    data = Dataset(d.t, d.u, d.m, y, d.input_names, d.flow_names, d.output_names)
    kw = {"optimizer": "lbfgs", "fixed": {"sigma_v": 1.0, "sigma_w_Ti": 1e-6, "sigma_w_Tw": 1e-6}}
    ml = fit(NET2, data, ["Rw"], method="ml", **kw)
    se_log = ml.std_errors["Rw"] / ml.estimates["Rw"]  # from the ML Hessian in log space
    w = min(1.0, float(np.median(np.diff(d.t))) / correlation_time)
    p_lik, p_prior = w / se_log**2, 1 / PRIOR_SPREAD**2
    expected = (p_lik * np.log(ml.estimates["Rw"]) + p_prior * np.log(0.01)) / (p_lik + p_prior)
    mp = fit(NET2, data, ["Rw"], method="map", options={"correlation_time_s": correlation_time}, **kw)
    assert np.log(mp.estimates["Rw"]) == pytest.approx(expected, abs=0.1 * abs(expected - np.log(0.01)))
    if w < 0.1:  # tempered to the information of 5 samples: the prior holds the estimate back
        assert abs(np.log(mp.estimates["Rw"] / ml.estimates["Rw"])) > 0.2
    # and the posterior standard error combines the two precisions
    assert mp.std_errors["Rw"] / mp.estimates["Rw"] == pytest.approx((p_lik + p_prior) ** -0.5, rel=0.1)


def test_the_reported_end_is_the_lowest_unless_one_tied_with_it_has_its_hessian() -> None:
    from rczone.estimation.minimize import COST_TIE, winning_end
    from rczone.estimation.optimize import StartOutcome

    def end(cost: float, hessian: bool) -> StartOutcome:
        x = np.ones(2)
        return StartOutcome(x, x, cost, True, 10, "", np.eye(2) if hessian else None)

    cost = -680.5
    tied = cost + 0.5 * COST_TIE * abs(cost)  # equal to rounding
    assert winning_end([end(tied, True), end(cost, False)], [0, 1]) == 0
    assert winning_end([end(tied, False), end(cost, False)], [0, 1]) == 1
    lower = cost - 3 * COST_TIE * abs(cost)  # really lower: it wins whatever the Hessian
    assert winning_end([end(cost, True), end(lower, False)], [0, 1]) == 1
    assert winning_end([end(cost, True), end(lower, False), end(0.0, True)], [0, 1]) == 1
