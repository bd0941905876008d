"""The verdict column of docs/validation.md's tables (``validation/verdicts.py``, issue 38).

The reasons come from rczone's own code where it writes them (the held-out checks, the robust
errors, the verdict of a fit on part of its data), so a reworded reason shows here as a name the
column no longer finds.
"""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from rczone.postfit.evidence import FAILED, PASSED, EvidenceCheck, HeldOutEvidence
from rczone.results.verdict import verdict_of

from .scripts import ROOT, load_script


class _Estimate(SimpleNamespace):
    pass


def _fit(flags=(), parameters=None):
    return SimpleNamespace(
        flags=tuple(flags), parameters=parameters or {}, issues=("at_bound",) if flags else ()
    )


def test_a_fit_without_a_reason_is_trustworthy_and_a_flagged_one_names_its_checks():
    cells = load_script("verdicts")
    assert cells.verdict_cell(verdict_of(_fit())) == "trustworthy"
    evidence = HeldOutEvidence(
        (
            EvidenceCheck("coverage", FAILED, "the 2-sigma band covers 68% at 72 steps (6 h)"),
            EvidenceCheck("baselines", PASSED, "no baseline beats the model"),
            EvidenceCheck("innovations", FAILED, "not white"),
        )
    )
    v = verdict_of(_fit(["Rea is at a bound", "Ci is at a bound"]), evidence=evidence)
    assert cells.verdict_cell(v) == (
        "flagged: Rea at a bound, Ci at a bound, held-out coverage, held-out innovations"
    )
    assert cells.verdict_cell(v._asdict()) == cells.verdict_cell(v)  # the JSON form reads the same


def test_the_robust_errors_and_dropped_samples_are_named():
    cells = load_script("verdicts")
    e = _Estimate(kind="capacitance", value=1e6, std_error=1e4, at_bound=False)
    robust = SimpleNamespace(std_errors={"Ci": 2e6})
    used = {"samples": 50, "of": 100, "fraction": 0.5, "missing": []}
    v = verdict_of(_fit(parameters={"Ci": e}), robust=robust, white=False, data_used=used)
    assert cells.verdict_cell(v) == "flagged: inputs missing, Ci robust SE >= 100 %"


@pytest.mark.parametrize(
    ("reason", "name"),
    [
        ("Hessian not positive definite: the parameters are not identifiable from these data", "Hessian not positive definite"),
        ("no standard error for Ci, Ce", "no standard error (Ci, Ce)"),
        ("not converged: the search has not settled", "not converged"),
        ("starts that reach the same cost disagree on Rie (0.001 to 0.003): the data do not determine it", "starts disagree on Rie"),
        ("a value of Cm ten times larger fits these data about as well", "Cm flat profile"),
        ("Rea fitted to A (0.01) and to B (0.02) disagree beyond their standard errors", "Rea disagrees on other data"),
        ("implausible data: Ti above 60 degC", "implausible data"),
        ("something new that no pattern names yet at all", "something new that no pattern names …"),
    ],
)  # fmt: skip
def test_every_kind_of_reason_has_a_short_name(reason, name):
    assert load_script("verdicts").check_name(reason) == name


def test_the_real_data_tables_carry_the_verdict():
    """The tables ``validation/real_data.py`` prints have the verdict column, in docs/validation.md's form."""
    mod = load_script("real_data")
    p = {"estimate": 4.84e6, "std_error": 0.09e6, "at_bound": False}
    m = {
        "parameters": dict.fromkeys(mod.SHOWN["bacher_madsen_prbs"], p),
        "calibration_rmse_K": 0.4,
        "validation_rmse_K": 0.7,
        "validation_max_error_K": 1.7,
        "verdict": {"trustworthy": False, "reasons": ["held out, baselines failed: beaten by arx"]},
    }
    table = mod.markdown({"bacher_madsen_prbs": {"methods": {"ml": m}}})
    head, rule, row = table.splitlines()
    assert rule == "|---|" + "---|" * 9
    assert head.endswith("| verdict |") and row.endswith("| flagged: held-out baselines |")
    assert "| ML | 4.84e6 ± 0.09e6 |" in row
    # tests/validation/test_real_data.py compares a fresh run's tables with docs/validation.md


#: docs/validation.md, whose tables the scripts below print.
PAGE = ROOT / "docs" / "validation.md"
#: A verdict as the JSON of ``rczone fit`` / ``select`` writes it, with two of rczone's own reasons.
FLAGGED = verdict_of(_fit(["Rea is at a bound"]), robust=None).to_dict()
TRUSTWORTHY = verdict_of(_fit()).to_dict()


def _head_on_page(table: str) -> str:
    """The table's header line, which docs/validation.md must show (the table regenerated with the column)."""
    head = table.splitlines()[0]
    assert head in PAGE.read_text(), f"docs/validation.md has no table headed\n{head}"
    return head


def test_the_model_selection_tables_carry_each_candidates_verdict():
    """``validation/model_selection.py`` prints the verdict ``select --json`` gives each candidate."""
    mod = load_script("model_selection")
    inn = {"ljung_box_p": 1e-20, "white": False}
    row = {"loglik": 2476.3, "n_params": 5, "aic": -4942.7, "bic": -4915.5, "innovations": inn}
    res = {
        "selected": "TiTh+heater+solar",
        "models": {
            "Ti+heater+solar": {**row, "trustworthy": True, "flags": [], "verdict": TRUSTWORTHY},
            "TiTh+heater+solar": {
                **row,
                "trustworthy": False,
                "flags": FLAGGED["reasons"],
                "verdict": FLAGGED,
            },
        },
        "forward": {"path": ["Ti+heater+solar", "TiTh+heater+solar"], "steps": []},
    }
    head, rule, ti, tith = mod.markdown(res).splitlines()[:4]
    assert head.endswith("| white | verdict |") and rule.count("---") == 8
    assert ti.endswith("| no | trustworthy |")
    assert tith.startswith("| TiTh+heater+solar **(selected)** |") and tith.endswith(
        "| flagged: Rea at a bound |"
    )
    _head_on_page(head)


def test_the_members_table_carries_each_fits_verdict():
    """``validation/holdout_bands.py --only members``: the verdict of ``rczone fit --holdout`` beside each member."""
    mod = load_script("holdout_bands")
    keys = [mod._steps_key(k) for k in mod.MEMBER_HORIZONS]
    scores = {"coverage": dict.fromkeys(keys, 0.99), "rmse_K": dict.fromkeys(keys, 0.1)}
    rows = {
        "TiTmThTsn+heater+solar (selected, noise all)": {
            "model": scores,
            "at_bound": [],
            "verdict": TRUSTWORTHY,
        },
        "TiTe+heater+solar (noise measured)": {
            "model": scores,
            "at_bound": ["Rea is at a bound"],
            "verdict": FLAGGED,
        },
        "TiTe+heater+solar (noise all)": {"model": scores, "at_bound": [], "verdict": None},
    }
    lines = mod.members_markdown(rows).splitlines()
    assert lines[0].endswith("| at a bound | verdict |") and lines[1].count("---") == len(keys) + 3
    assert lines[2].startswith("| TiTmThTsn, selected, noise all |") and lines[2].endswith(
        "| none | trustworthy |"
    )
    assert lines[3].startswith("| TiTe, noise measured |") and lines[3].endswith(
        "| Rea | flagged: Rea at a bound |"
    )
    assert lines[4].endswith("| not recorded |")  # never a verdict that was not given
    _head_on_page(lines[0])


def test_the_latent_force_table_carries_each_fits_verdict():
    mod = load_script("latent_force")
    fit_row = {
        "loglik": 118.5,
        "n_params": 6,
        "ljung_box_p": 0.019,
        "rmse_6h_K": 0.378,
        "at_bound": ["sigma_v"],
    }
    res = {
        "armadillo_pysip": {
            "noise": "measured",
            "without": {**fit_row, "model": "TiTe+heater", "verdict": FLAGGED},
            "with": {**fit_row, "model": "TiTe+heater+Qd (matern32)", "verdict": TRUSTWORTHY},
            "test": {"statistic": 97.1, "df": 2, "p_value": 8e-22, "selected": "with"},
        }
    }
    head, _, without, with_ = mod.markdown(res).splitlines()
    assert head.endswith("| at a bound | verdict |")
    assert without.endswith("| sigma_v | flagged: Rea at a bound |")
    assert "**(selected)**" in with_ and with_.endswith("| sigma_v | trustworthy |")
    _head_on_page(head)


def test_the_kstep_table_carries_the_verdict_of_both_fits():
    mod = load_script("kstep_vs_ml")
    score = {"rmse_K": 0.3, "interval_score_K": 2.0, "coverage_2sigma": 0.8}
    fits = {"scores": {"1": score, "12": score}}
    res = {
        "bacher_madsen_prbs": {
            "model": "TiTe+heater+solar",
            "dt_s": 300.0,
            "ml": {**fits, "verdict": FLAGGED},
            "kstep": {**fits, "verdict": TRUSTWORTHY},
        }
    }
    head, _, first, second = mod.markdown(res).splitlines()
    assert head.endswith("| verdict ML | verdict k-step |")
    assert first.startswith("| Bacher–Madsen | TiTe+heater+solar | 5 min |")
    assert first.endswith("| flagged: Rea at a bound | trustworthy |")
    assert second.startswith("| | | 1 h |") and second.endswith("| | |")  # the verdicts once per fit
    _head_on_page(head)
