"""The expected standard errors of diagnose agree with the spread of real fits (Monte Carlo).

Noisy replicates of one forced-response night are simulated from the paper's reduced model
with white measurement noise; each is fitted by output-error least squares. The spread of
log-estimates must agree with the Fisher-information prediction within a factor of 1.5
(issue 5). The diagnose settings match the experiment: white noise (correlation time = one
sample), no unknown heat gain, and the initial state unknown (the fit estimates it, diagnose
marginalizes it). With the initial wall state instead guessed from the first noisy sample,
the spread of Rw doubles: that guess is an error source the Fisher model does not contain.
"""

import numpy as np

from rczone.calibration import calibrate
from rczone.diagnostics import diagnose
from rczone.models import get_model
from rczone.simulation import simulate
from rczone.simulation.initial import output_consistent_state
from tests.unit.diagnostics.synthetic import night

TRUTH = {"Cr": 6e5, "Rw": 0.012}
SIGMA = 0.1


def test_expected_standard_errors_match_monte_carlo_spread():
    net = get_model("second-order-paper")
    base = night("forced", seed=0, hours=8)
    ss = net.state_space(TRUTH)
    t = base["time"].to_numpy()
    u = base[list(net.input_names)].to_numpy()
    m = base[["m"]].to_numpy()
    x0 = output_consistent_state(ss, u[0], m[0], 22.0)
    clean = simulate(ss, t, u, m, x0=x0).y[:, 0]
    rng = np.random.default_rng(123)
    logs = []
    for _ in range(24):
        frame = base.copy()
        frame["Ti"] = clean + SIGMA * rng.standard_normal(t.size)
        cal = calibrate(net, frame, method="ls", free=["Cr", "Rw", "x0_Ti", "x0_Tw"], uncertainty=False)
        logs.append([np.log(cal.result.estimates[n]) for n in ("Cr", "Rw")])
    spread = np.std(np.array(logs), axis=0, ddof=1)
    frame = base.copy()
    frame["Ti"] = clean
    rep = diagnose(
        net,
        frame,
        free=["Cr", "Rw"],
        theta=TRUTH,
        sigma_K=SIGMA,
        correlation_time_s=60.0,
        heat_input=None,
        initial_state_nuisance=False,
    )
    ratio = spread / rep.expected_se
    assert np.all(ratio > 1 / 1.5) and np.all(ratio < 1.5), (spread, rep.expected_se)
    # and the estimates are centred on the truth within their spread
    bias = np.mean(np.array(logs), axis=0) - np.log([TRUTH["Cr"], TRUTH["Rw"]])
    assert np.all(np.abs(bias) < 3 * spread / np.sqrt(24) + 0.01)
