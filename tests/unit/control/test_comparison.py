"""Paired comparisons over seeds: the pairing, the differences, the verdicts, the CLI."""

import json

import numpy as np
import pytest

from rczone.cli.main import main
from rczone.control.comparison import KPIS, Entry, Scenario, compare, verdict
from rczone.errors import ParameterError


@pytest.fixture(scope="module")
def cmp():
    entries = [Entry("naive", "naive"), Entry("again", "naive"), Entry("commissioned", "thermostat")]
    return compare(entries, [3, 4], scenario=Scenario("winter", days=0.05))


def test_a_controller_paired_with_itself_differs_by_nothing_on_every_seed(cmp):
    rows = {(r["entry"], r["kpi"]): r for r in cmp.rows()}
    for k in KPIS:
        np.testing.assert_array_equal(cmp.scores["again"][k], cmp.scores["naive"][k])
        assert rows["again", k]["diff_mean"] == 0.0 and rows["again", k]["verdict"] == "no difference"
        d = cmp.scores["commissioned"][k] - cmp.scores["naive"][k]
        assert rows["commissioned", k]["diff_mean"] == pytest.approx(d.mean())
        assert rows["commissioned", k]["diff_sd"] == pytest.approx(d.std(ddof=1))
    assert not np.array_equal(cmp.scores["naive"]["energy_kWh"][0], cmp.scores["naive"]["energy_kWh"][1])
    assert set(cmp.setup["constraints"]) == {3, 4} and "reference: naive" in cmp.summary()
    assert len(cmp.to_frame()) == 3 * len(KPIS) and cmp.to_dict()["seeds"] == [3, 4]


@pytest.mark.parametrize(
    ("diff", "ref", "expected"),
    [
        ([-1.0, -1.2, -0.9], 10.0, "better"),
        ([1.0, 1.2, 0.9], 10.0, "worse"),
        ([-1.0, 1.2, -0.1], 10.0, "no difference"),  # within two standard errors
        ([0.01, 0.011, 0.012], 10.0, "no difference"),  # below 1 % of the reference
        ([-1.0], 10.0, "one seed"),
    ],
)
def test_the_verdict_needs_a_difference_beyond_its_spread_and_beyond_one_percent(diff, ref, expected):
    assert verdict(np.array(diff), ref) == expected


def test_a_comparison_needs_two_distinct_entries_and_distinct_seeds():
    with pytest.raises(ParameterError, match="two or more"):
        compare([Entry("a", "naive")], [1])
    with pytest.raises(ParameterError, match="distinct labels"):
        compare([Entry("a", "naive"), Entry("a", "thermostat")], [1])
    with pytest.raises(ParameterError, match="seeds"):
        compare([Entry("a", "naive"), Entry("b", "thermostat")], [1, 1])


def test_control_test_compare_writes_the_paired_table(tmp_path, capsys):
    out = tmp_path / "cmp.json"
    args = [
        "control-test",
        "--compare",
        "naive,thermostat",
        "--seeds",
        "2",
        "--days",
        "0.02",
        "--json",
        str(out),
    ]
    assert main(args) == 0
    doc = json.loads(out.read_text())
    assert doc["seeds"] == [0, 1] and {r["entry"] for r in doc["rows"]} == {"naive", "thermostat"}
    assert "paired comparison" in capsys.readouterr().out
    for bad, match in (
        (["--compare", "naive,,mpc"], "empty"),
        (["--compare", "naive,mpc", "--seeds", "0"], "seeds"),
    ):
        assert main(["control-test", *bad, "--days", "0.02"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and match in err


def test_an_entry_is_paired_against_the_entry_it_names():
    entries = [
        Entry("naive", "naive"),
        Entry("commissioned", "thermostat"),
        Entry("again", "thermostat", reference="commissioned"),
    ]
    cmp = compare(entries, [3, 4], scenario=Scenario("winter", days=0.02))
    rows = {(r["entry"], r["kpi"]): r for r in cmp.rows()}
    for k in KPIS:
        assert rows["again", k]["against"] == "commissioned" and rows["again", k]["diff_mean"] == 0.0
        d = cmp.scores["commissioned"][k] - cmp.scores["naive"][k]
        assert rows["commissioned", k]["diff_mean"] == pytest.approx(d.mean())
    table = cmp.markdown().splitlines()
    assert len(table) == 2 + 3 and table[-1].startswith("| again | commissioned |")
    with pytest.raises(ParameterError, match="not an entry"):
        compare([Entry("a", "naive"), Entry("b", "naive", reference="c")], [1])


def test_control_test_study_refuses_unknown_studies_in_one_line(capsys):
    for bad, match in (
        (["--study", "papr"], "paper"),
        (["--study", "paper", "--compare", "naive,thermostat"], "not both"),
    ):
        assert main(["control-test", *bad, "--days", "0.02"]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and match in err
