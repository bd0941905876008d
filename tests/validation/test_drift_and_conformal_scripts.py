"""The tables of validation/drift_virtual.py and validation/conformal_holdout.py count what they say."""

from __future__ import annotations

from tests.validation.scripts import load_script


def _run(seed, drifted, detected=None, since=None):
    return {
        "seed": seed,
        "drifted": drifted,
        "detected_d": detected,
        "since_d": since,
        "tests": [],
        "cpu_s": 0.1,
    }


def test_the_drift_table_counts_alarms_delays_and_false_alarms():
    m = load_script("drift_virtual")
    results = {
        "Rea halved from day 4": [_run(1, True, 4.25, 3.9), _run(2, True, 5.5, 4.0), _run(3, False)],
        "unchanged, ten days scored": [_run(1, False), _run(2, True, 6.5, 5.5), _run(3, False)],
    }
    rea, unchanged = m.markdown(results).splitlines()[2:]
    # two of three flagged, one within a day (0.25 d); median delay of 0.25 and 1.5 is 0.875, max 1.5
    assert rea == "| Rea halved from day 4 | 3 | 2 | 1 | 0.88 (1.50) | 3.95 |"
    assert "| 3 | 1 false alarm(s) |" in unchanged


def test_write_doc_replaces_only_the_text_between_its_markers(tmp_path):
    m = load_script("drift_virtual")
    doc = tmp_path / "v.md"
    doc.write_text(f"before\n{m.START}\nold\n{m.END}\nafter \\1\n")
    m.write_doc(doc, "| new | \\d |")
    assert doc.read_text() == f"before\n{m.START}\n| new | \\d |\n{m.END}\nafter \\1\n"


def test_a_named_table_goes_between_its_own_markers_only(tmp_path):
    m = load_script("drift_virtual")
    fresh = m.markers("fresh")
    assert fresh == ("<!-- drift-virtual-fresh:start -->", "<!-- drift-virtual-fresh:end -->")
    assert m.markers(None) == (m.START, m.END)
    doc = tmp_path / "v.md"
    doc.write_text(f"{m.START}\nold\n{m.END}\n{fresh[0]}\nold\n{fresh[1]}\n")
    m.write_doc(doc, "new", fresh)
    assert doc.read_text() == f"{m.START}\nold\n{m.END}\n{fresh[0]}\nnew\n{fresh[1]}\n"


def test_the_conformal_rule_is_coverage_in_85_99_and_a_score_no_worse():
    m = load_script("conformal_holdout")

    def band(cov, score):
        return {"1": {"coverage": cov, "interval_score_K": score, "rmse_K": 0.1}}

    results = {
        "x": {
            "model": "M",
            "dt_s": 300.0,
            "bands": {
                "in-sample factors": band(0.99, 1.0),
                "split conformal": band(1.0, 0.9),  # covers too much
                "conformal, online": band(0.85, 1.0),  # at the edges: holds
            },
        }
    }
    split, online = m.verdicts(results)
    assert split == "x, split conformal: fails at 5 min (coverage)"
    assert online == "x, conformal, online: meets the rule at every horizon"
    results["x"]["bands"]["conformal, online"] = band(0.9, 1.01)
    assert m.verdicts(results)[1] == "x, conformal, online: fails at 5 min (score)"
