"""The paper study's entries: Q1 against the 13-state MPC, Q2's closed-loop fit against the forced one."""

import pytest

from rczone.control.comparison import Scenario, compare
from rczone.control.study import NO_DISTURBANCE, REFERENCE, paper_entries, study_entries
from rczone.errors import ParameterError
from rczone.models import load_model


def construction(name, night):
    return load_model(name)  # the fits' stand-in: the study's wiring, not the fits, is tested here


def test_the_paper_study_pairs_q1_with_the_full_model_and_q2_closed_loop_with_forced():
    entries = paper_entries(fit=construction)
    assert entries[0].label == REFERENCE and entries[0].model.state_space().n_states == 13
    assert [e.model.state_space().n_states for e in entries[1:3]] == [2, 1]
    q2 = [e for e in entries if e.label.startswith("Q2")]
    assert q2[1].reference == q2[0].label and entries[-1].controller == "thermostat"
    blind = next(e for e in entries if e.label == NO_DISTURBANCE)
    assert not blind.disturbance and blind.reference == "Q1 2-state"
    assert all(e.disturbance for e in entries if e is not blind)
    with pytest.raises(ParameterError, match="paper"):
        study_entries("papers")


@pytest.mark.slow
def test_the_paper_study_runs_as_one_paired_comparison():
    entries = paper_entries(fit=construction)
    cmp = compare(entries, [5, 6], scenario=Scenario("summer", days=0.02))
    rows = {(r["entry"], r["kpi"]): r for r in cmp.rows()}
    q2 = [e.label for e in entries if e.label.startswith("Q2")]
    # with the same model on both sides the closed-loop "fit" differs from the forced by nothing
    assert rows[q2[1], "energy_kWh"]["diff_mean"] == 0.0 and rows[q2[1], "energy_kWh"]["against"] == q2[0]
    assert rows["Q1 2-state", "energy_kWh"]["against"] == REFERENCE
    assert len(cmp.markdown().splitlines()) == 2 + len(entries)
