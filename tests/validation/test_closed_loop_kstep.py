"""validation/closed_loop_kstep.py: the k-step MPC is paired with the ML MPC seed by seed, and the page gets the tables."""

import json
import statistics

import numpy as np

from rczone.control.comparison import KPIS, Comparison
from rczone.models import load_model
from tests.validation.scripts import load_script


def _comparison(script, oracle=True):
    ml = {k: np.array([1.0, 5.0, 9.0, 13.0]) for k in KPIS}  # the seeds differ widely...
    ks = {k: v + np.array([0.1, 0.2, 0.1, 0.2]) for k, v in ml.items()}  # ...the pairs do not
    scores = {script.ML: ml, script.KSTEP: ks}
    if oracle:
        scores[script.ORACLE] = {k: v - 0.5 for k, v in ml.items()}
    return Comparison(tuple(scores), (5, 6, 7, 8), scores, {})


def test_the_difference_is_paired_by_seed_with_its_standard_error():
    script = load_script("closed_loop_kstep")
    p = script.paired(_comparison(script), "energy_kWh")
    diffs = [0.1, 0.2, 0.1, 0.2]
    assert np.isclose(p["mean"], statistics.fmean(diffs))
    assert np.isclose(p["se"], statistics.stdev(diffs) / 2)  # unpaired, the spread would be ~30 times this
    assert p["verdict"] == "worse"  # 0.15 beyond two standard errors and 1 % of the ML mean
    assert np.allclose(p["per_seed"], diffs)


def test_main_pastes_both_tables_between_the_markers(tmp_path, monkeypatch):
    script = load_script("closed_loop_kstep")
    zm = load_model("second-order-paper").with_values({}, {"sigma_v": 0.01, "sigma_w_Ti": 0.02})
    fake = {
        "models": {script.ML: zm, script.KSTEP: zm},
        "rmse": {script.ML: {10: 0.1, 60: 0.2}, script.KSTEP: {10: 0.1, 60: 0.3}},
        "criterion": {script.ML: 2.0, script.KSTEP: 1.5},
        "results": {"summer": _comparison(script), "winter": _comparison(script, oracle=False)},
    }
    monkeypatch.setattr(script, "run", lambda seeds, seasons, days, horizons, oracle, save, band: save(fake))
    page = tmp_path / "page.md"
    blocks = load_script("control_doc")
    page.write_text(
        "intro\n"
        + blocks.block("kstep-closed-loop", "old")
        + "\n"
        + blocks.block("kstep-closed-loop-fits", "old")
        + "\nend\n"
    )
    assert script.main(["--page", str(page), "--out", str(tmp_path)]) == 0
    found = blocks.blocks(page.read_text())
    assert "python validation/closed_loop_kstep.py --page" in found["kstep-closed-loop"]
    rows = [r for r in found["kstep-closed-loop"].splitlines() if r.startswith("| summer | energy_kWh")]
    assert rows == ["| summer | energy_kWh | 7 | 7.15 | +0.15 ± 0.029 | worse | 6.5 |"]
    assert "| winter | energy_kWh | 7 | 7.15 | +0.15 ± 0.029 | worse | - |" in found["kstep-closed-loop"]
    assert (
        "| k-step fit on C |" in found["kstep-closed-loop-fits"]
        and "RMSE 60 min on A (K)" in found["kstep-closed-loop-fits"]
    )
    saved = json.loads((tmp_path / "closed_loop_kstep.json").read_text())
    assert saved["paired"]["summer"]["comfort_Kh"]["verdict"] == "worse"
