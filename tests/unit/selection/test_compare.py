"""Model selection on data simulated from a known structure: the right model, white innovations."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rczone.errors import DataError, ParameterError
from rczone.models import load_model
from rczone.selection.compare import candidate_free, family_candidates, likelihood_ratio_test, select_models
from rczone.selection.nesting import nesting

from .synthetic import TRUE_MODEL, prbs_zone

SIMPLER, RICHER = "Ti+heater", "TiTe+heater+solar"  # Ps in the data does nothing
CANDIDATES = [SIMPLER, TRUE_MODEL, RICHER]


@pytest.fixture(scope="module")
def zone():
    return prbs_zone(days=3, seed=1)


@pytest.fixture(scope="module")
def by_bic(zone):
    return select_models(CANDIDATES, zone)


def test_bic_selects_the_true_structure_over_a_simpler_and_a_richer_nested_one(by_bic):
    sel = by_bic
    assert sel.selected == TRUE_MODEL and sel.rule == "bic"
    c = sel.candidates
    # the richer model nests the true one (Aw = 0): its optimum is at least as high, up to the search's
    # tolerance (its gradient search stops just inside the box, a few 1e-6 of log L below Aw = 0);
    # 1e-3 is still a thousand times below what would move a likelihood-ratio test (1.92 at 5 %)
    assert c[SIMPLER].loglik < c[TRUE_MODEL].loglik <= c[RICHER].loglik + 1e-3
    # R, C, Aw, the measurement noise and the process noise of every state
    assert [c[n].n_params for n in CANDIDATES] == [4, 7, 8]
    n = sel.samples["n_obs"]
    assert c[TRUE_MODEL].bic == pytest.approx(7 * np.log(n) - 2 * c[TRUE_MODEL].loglik)
    assert c[TRUE_MODEL].aic == pytest.approx(14 - 2 * c[TRUE_MODEL].loglik)
    df = sel.to_frame()
    assert list(df.index) == list(CANDIDATES) and df.loc[TRUE_MODEL, "selected"] == "<-"


def test_the_true_structure_has_white_innovations_and_the_too_simple_one_not(by_bic):
    inn = {n: by_bic.candidates[n].calibration.innovations for n in CANDIDATES}
    assert inn[TRUE_MODEL].white and inn[TRUE_MODEL].ljung_box_p > 0.05
    assert not inn[SIMPLER].white and inn[SIMPLER].ljung_box_p < 1e-3


def test_likelihood_ratio_tests_between_the_detected_nested_pairs(by_bic):
    tests = {(t.simple, t.rich): t for t in by_bic.tests}
    assert set(tests) == {(SIMPLER, TRUE_MODEL), (SIMPLER, RICHER), (TRUE_MODEL, RICHER)}
    t = tests[(SIMPLER, TRUE_MODEL)]
    assert t.df == 3 and t.p_value < 1e-10 and t.rejects(0.05)
    t = tests[(TRUE_MODEL, RICHER)]
    assert t.df == 1 and t.nesting.describe() == "Aw = 0" and not t.rejects(0.05)
    assert t.p_value_chi_bar <= t.p_value  # the boundary mixture is less conservative
    d = by_bic.to_dict()
    assert d["selected"] == TRUE_MODEL and d["selected_white"] is True
    m = d["models"][TRUE_MODEL]
    assert {"loglik", "n_params", "aic", "bic"} <= set(m)
    assert m["innovations"]["ljung_box_p"] == pytest.approx(
        by_bic.candidates[TRUE_MODEL].calibration.innovations.ljung_box_p
    )
    assert {"simple", "rich", "statistic", "df", "p_value", "restriction"} <= set(d["tests"][0])


def test_forward_selection_grows_from_the_simplest_and_stops_at_the_truth(zone):
    sel = select_models(CANDIDATES, zone, forward=True)
    assert sel.selected == TRUE_MODEL and sel.rule == "forward"
    assert sel.path == (SIMPLER, TRUE_MODEL)
    first, second = sel.steps
    assert first["tried"] == [TRUE_MODEL] and first["accepted"]  # the smallest extension only
    assert second["best"] == RICHER and not second["accepted"]


def test_a_richer_fit_below_its_special_case_is_reported_not_hidden(by_bic):
    better, worse = by_bic.candidates[TRUE_MODEL], by_bic.candidates[SIMPLER]
    nest = nesting(worse.calibration.model.network, better.calibration.model.network)
    t = likelihood_ratio_test(better, worse, nest)  # as if the richer fit had ended below: LR < 0
    assert t.statistic < 0 and t.p_value == 1.0


def test_every_candidate_is_fitted_on_the_same_samples(zone):
    gappy = zone.copy()
    gappy.loc[10:20, "Ps"] = np.nan  # only the richer model reads Ps
    sel = select_models([SIMPLER, RICHER], gappy.iloc[:300], n_starts=1)
    assert [c.n_obs for c in sel.candidates.values()] == [279, 279]
    assert sel.samples["n"] == 300 - 21
    assert sel.samples["start_s"] == pytest.approx(float(zone["time"].iloc[21]))


@pytest.mark.parametrize(
    ("models", "kwargs", "error", "match"),
    [
        ([SIMPLER], {}, ParameterError, "at least two"),
        ([SIMPLER, SIMPLER], {}, ParameterError, "given twice"),
        ([SIMPLER, TRUE_MODEL], {"rule": "hqc"}, ParameterError, "rule must be"),
        ([SIMPLER, TRUE_MODEL], {"alpha": 1.5}, ParameterError, "alpha must be"),
        ([SIMPLER, TRUE_MODEL], {"noise": "some"}, ParameterError, "noise must be"),
        ([SIMPLER, "TiTe+heater+air"], {}, DataError, "Ts"),
    ],
)
def test_bad_selections(zone, models, kwargs, error, match):
    with pytest.raises(error, match=match):
        select_models(models, zone.iloc[:50], **kwargs)


def test_a_richer_fit_that_ends_below_a_nested_model_is_retried_from_it(zone, monkeypatch):
    """One local search from a poor start ends below the simpler model: the fit is repeated from it.

    The default gradient search reaches the richer model's optimum from this start; a direct search
    (Nelder-Mead) does not, which makes the case the retry is for.
    """
    import rczone.selection.compare as compare

    direct = compare.calibrate
    monkeypatch.setattr(compare, "calibrate", lambda *a, **k: direct(*a, **k, optimizer="nelder-mead"))
    zm = load_model(TRUE_MODEL)
    # a box of a room's size, and a start in its corner the single local search cannot leave
    box = {"Ci": (1e4, 1e9), "Ce": (1e5, 1e10), "Rie": (1e-6, 1.0), "Rea": (1e-5, 10.0)}
    params = [dataclasses.replace(p, bounds=box.get(n, p.bounds)) for n, p in zm.network.parameters.items()]
    room = dataclasses.replace(zm, network=zm.network.replace_parameters(params))
    poor = room.with_values({"Ci": 2e4, "Ce": 5e9, "Rie": 2e-6, "Rea": 5.0})
    sel = select_models([SIMPLER, poor], zone, n_starts=1)
    simple, rich = sel.candidates[SIMPLER], sel.candidates[TRUE_MODEL]
    assert rich.retried and rich.loglik > simple.loglik
    assert sel.to_dict()["models"][TRUE_MODEL]["retried_from_simpler"] is True


def test_candidate_conventions():
    net = load_model("TiTe+heater").network
    assert candidate_free(net) == ("Ci", "Ce", "Rie", "Rea", "sigma_v", "sigma_w_Ti", "sigma_w_Te")
    assert candidate_free(net, "measured") == ("Ci", "Ce", "Rie", "Rea", "sigma_v", "sigma_w_Ti")
    assert family_candidates(["time", "Ti", "To", "Ph", "Ps"]) == [
        "Ti+heater+solar",
        "TiTe+heater+solar",
        "TiTh+heater+solar",
        "TiTeTh+heater+solar",
        "TiTm+heater+solar",
    ]
    assert family_candidates(["Ti", "To", "m", "Ts"])[0] == "Ti+air"


def test_forward_steps_through_the_whole_family_are_one_part_richer_and_nested():
    """60 candidates with solar data, 24 without; a step adds one part, and the structural rule confirms it."""
    from rczone.selection.compare import _Nestings

    assert len(family_candidates(["Ti", "To", "Ph"], extended=True)) == 24  # no Ae, As without Ps
    names = family_candidates(["Ti", "To", "Ph", "Ps"], extended=True)
    assert len(names) == 60 and names[0] == "Ti+heater+solar"
    models = {n: load_model(n) for n in names}
    nests = _Nestings(models, {n: candidate_free(m.network) for n, m in models.items()})
    steps = nests.smallest_extensions("TiTeTh+heater+solar", ["Ti+heater+solar", "TiTh+heater+solar"])
    assert steps == [f"{b}+heater+solar" for b in ("TiTmTeTh", "TiTeThTsn", "TiTeThAe", "TiTeThRia")]
    assert nests.get("TiTeTh+heater+solar", "TiTeThRia+heater+solar").describe() == "Ria -> ∞"
    assert set(nests.cache) == {("TiTeTh+heater+solar", s) for s in steps}  # nothing else was analysed


def test_a_warm_start_from_a_measurement_noise_at_its_floor_starts_inside_the_box(zone):
    """The simpler fit's sigma_v on the data's floor (its lower bound) is carried 1 % inside, not refused."""
    from types import SimpleNamespace

    from rczone.calibration import calibrate
    from rczone.estimation.resolution import noise_floor
    from rczone.selection.compare import _warm_start

    floor = noise_floor(zone["Ti"].to_numpy(float))
    simple = load_model(SIMPLER)
    simple = simple.with_values({}, {**simple.noise, "sigma_v": floor})
    rich = load_model(TRUE_MODEL)
    free = candidate_free(rich.network)
    nest = nesting(simple.network, rich.network, candidate_free(simple.network), free)
    warm = _warm_start(rich, SimpleNamespace(calibration=SimpleNamespace(model=simple)), nest)
    assert warm.noise["sigma_v"] == pytest.approx(1.01 * floor, rel=1e-12)
    assert calibrate(warm, zone, method="ml", free=free, n_starts=1).result.llf > 0  # the start is accepted
