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

from .scripts import load_script


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
