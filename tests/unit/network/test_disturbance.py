"""Latent-force disturbances: the GP's SDE against its kernel, the network's assembly, bad input.

Oracles: the closed-form Matérn and damped-cosine kernels (Rasmussen & Williams 2006, eq. 4.17),
the stationary covariance from scipy's Lyapunov solver, Van Loan's block matrix exponential with
scipy's ``expm``, and sample covariances of seeded draws.
"""

import math

import numpy as np
import pytest
from scipy.linalg import expm, solve_continuous_lyapunov

from rczone.errors import NetworkError, ParameterError
from rczone.estimation.data import Dataset
from rczone.estimation.engines import general_cost
from rczone.estimation.kalman import stochastic_matrices
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor
from rczone.network.disturbance import KINDS, LatentForce, covariance_function, latent_sde

ELL, PERIOD = 3 * 3600.0, 86400.0
LAGS = np.array([0.0, 600.0, 3600.0, 4 * 3600.0, 11 * 3600.0, 30 * 3600.0])


def stationary(kind):
    sde = latent_sde(kind, ELL, PERIOD if kind == "periodic" else None)
    return sde, solve_continuous_lyapunov(sde.F, -np.diag(sde.qc))


@pytest.mark.parametrize("kind", list(KINDS))
def test_sde_stationary_covariance_function_equals_the_kernel(kind):
    """k(tau) = H expm(F tau) P_inf H' for the SDE equals the closed-form kernel at every lag."""
    sde, P = stationary(kind)
    assert P[0, 0] == pytest.approx(1.0, rel=1e-12)  # unit variance: the magnitude is the std in W
    period = PERIOD if kind == "periodic" else None
    want = covariance_function(kind, LAGS, magnitude=1.0, length_scale=ELL, period=period)
    got = np.array([(expm(sde.F * tau) @ P)[0, 0] for tau in LAGS])
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)
    # the kernel scales with the magnitude squared
    assert covariance_function(
        kind, 3600.0, magnitude=250.0, length_scale=ELL, period=period
    ) == pytest.approx(250.0**2 * want[2], rel=1e-12)


def test_matern_kernels_have_their_textbook_values():
    """Spot values written out: Matern-3/2 at tau = ell is (1 + sqrt 3) e^-sqrt3; 5/2 has (1 + r + r^2/3) e^-r."""
    r3, r5 = math.sqrt(3.0), math.sqrt(5.0)
    assert covariance_function("matern32", ELL, magnitude=2.0, length_scale=ELL) == pytest.approx(
        4.0 * (1 + r3) * math.exp(-r3), rel=1e-13
    )
    assert covariance_function("matern52", ELL, magnitude=1.0, length_scale=ELL) == pytest.approx(
        (1 + r5 + 5 / 3) * math.exp(-r5), rel=1e-13
    )
    half = covariance_function("periodic", PERIOD / 2, magnitude=1.0, length_scale=ELL, period=PERIOD)
    assert half == pytest.approx(-math.exp(-PERIOD / 2 / ELL), rel=1e-13)


@pytest.mark.parametrize("kind", ["matern32", "periodic"])
def test_scaled_states_are_white_at_stationarity(kind):
    """The states are scaled so that P_inf = I: the filter's unit default initial spread is stationary."""
    np.testing.assert_allclose(stationary(kind)[1], np.eye(2), atol=1e-12)


def one_node(kind="matern32", magnitude="sd", **extra):
    period = {"period": "Pd"} if kind == "periodic" else {}
    return RCNetwork(
        "1R1C+d",
        nodes=[Node("Ti", "Ci"), Node("Tm", None)],
        boundaries=["To"],
        resistors=[Resistor("Ti", "Tm", "R1"), Resistor("Tm", "To", "R2")],
        heat_inputs=[HeatInput("Q", "Ti")],
        parameters=[
            Parameter("Ci", "capacitance", 2e6),
            Parameter("R1", "resistance", 0.004),
            Parameter("R2", "resistance", 0.006),
            Parameter("sd", "magnitude", 300.0),
            Parameter("ld", "time", ELL),
            Parameter("Pd", "time", PERIOD, fixed=True),
        ],
        disturbances=[
            LatentForce("Qd", kind, {"Ti": 0.4, "Tm": 0.6}, magnitude=magnitude, length_scale="ld", **period)
        ],
        **extra,
    )


def test_latent_states_follow_the_nodes_and_drive_them_through_the_gains():
    """Heat into the massless node reaches Ti through the Kron reduction: (0.4 + 0.6 R2/(R1+R2)) sd / Ci."""
    net = one_node(outputs=["Tm"])
    ss = net.state_space()
    assert ss.state_names == ("Ti", "Qd", "Qd_d1") and net.latent_state_names == ("Qd", "Qd_d1")
    R1, R2, Ci, sd = 0.004, 0.006, 2e6, 300.0
    assert ss.A[0, 1] == pytest.approx((0.4 + 0.6 * R2 / (R1 + R2)) * sd / Ci, rel=1e-12)
    assert ss.A[0, 2] == 0.0 and not ss.A[1:, 0].any() and not ss.B[1:].any()
    np.testing.assert_allclose(ss.A[1:, 1:], latent_sde("matern32", ELL).F, rtol=1e-14)
    # the output Tm sees the heat delivered at Tm directly: 0.6 sd R1 R2 / (R1 + R2) K per unit state
    assert ss.C[0, 1] == pytest.approx(0.6 * sd * R1 * R2 / (R1 + R2), rel=1e-12)
    np.testing.assert_allclose(ss.diffusion, [0.0, *latent_sde("matern32", ELL).qc], rtol=1e-14)
    assert np.isnan(ss.capacities[1:]).all()
    assert net.conductance_form is None  # the compiled conductance engines do not see latent states


@pytest.mark.parametrize("kind", list(KINDS))
def test_discretized_process_noise_matches_van_loan_and_the_stationary_identity(kind):
    """Qd of the filter's discretization = Van Loan's expm (scipy) = P_inf - Phi P_inf Phi' on the latent block."""
    net = one_node(kind)
    ss = net.state_space()
    dt = 900.0
    t = np.arange(3) * dt
    dyn = stochastic_matrices(ss, t, np.zeros((3, 0)), np.diag(ss.diffusion))
    n = ss.n_states
    vl = expm(np.block([[-ss.A, np.diag(ss.diffusion)], [np.zeros((n, n)), ss.A.T]]) * dt)
    Phi = vl[n:, n:].T
    Qd = Phi @ vl[:n, n:]
    np.testing.assert_allclose(dyn.Phi[0], Phi, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(dyn.Qd[0], Qd, rtol=1e-8, atol=1e-14 * np.abs(Qd).max())
    _, P = stationary(kind)
    lat = slice(1, n)
    np.testing.assert_allclose(dyn.Qd[0][lat, lat], P - Phi[lat, lat] @ P @ Phi[lat, lat].T, atol=1e-12)


@pytest.mark.parametrize("kind", list(KINDS))
def test_seeded_draws_have_the_kernel_as_covariance(kind):
    """20000 stationary chains stepped with the filter's (Phi, Qd): sample E[d(0) d(tau)] within 5 standard errors."""
    net = one_node(kind)
    ss = net.state_space()
    dt, steps, chains = 1800.0, 40, 20000
    dyn = stochastic_matrices(ss, np.arange(2) * dt, np.zeros((2, 0)), np.diag(ss.diffusion))
    lat = slice(1, ss.n_states)
    Phi, Qd = dyn.Phi[0][lat, lat], dyn.Qd[0][lat, lat]
    _, P = stationary(kind)
    rng = np.random.default_rng(20231)
    s = rng.standard_normal((chains, P.shape[0])) @ np.linalg.cholesky(P).T
    L = np.linalg.cholesky(Qd + 1e-300 * np.eye(P.shape[0]))
    first = s[:, 0].copy()
    period = PERIOD if kind == "periodic" else None
    for k in range(steps + 1):
        if k % 8 == 0:
            prod = first * s[:, 0]
            want = covariance_function(kind, k * dt, magnitude=1.0, length_scale=ELL, period=period)
            se = prod.std() / math.sqrt(chains)
            assert abs(prod.mean() - want) < 5 * se, (k, prod.mean(), want, se)
        s = s @ Phi.T + rng.standard_normal(s.shape) @ L.T


def synthetic(net, theta, n=300, dt=600.0, seed=3):
    """Measurements of ``net`` with its disturbance drawn from the GP (exact discretization), sigma_v = 0.02 K."""
    ss = net.state_space(theta)
    rng = np.random.default_rng(seed)
    t = np.arange(n) * dt
    u = np.column_stack([5 + 3 * np.sin(2 * np.pi * t / 86400), 800 * (np.sin(2 * np.pi * t / 36000) > 0)])
    dyn = stochastic_matrices(ss, t, np.zeros((n, 0)), np.diag(ss.diffusion))
    x = np.zeros((n, ss.n_states))
    x[0, 0] = 20.0
    L = np.linalg.cholesky(dyn.Qd[0] + 1e-18 * np.eye(ss.n_states))
    for k in range(n - 1):
        x[k + 1] = dyn.Phi[0] @ x[k] + dyn.G0[0] @ u[k] + L @ rng.standard_normal(ss.n_states)
    y = x @ ss.C.T + u @ ss.D.T + 0.02 * rng.standard_normal((n, 1))
    return Dataset(t, u, None, y, ss.input_names, (), ss.output_names)


NOISE = {"sigma_v": 0.02, "sigma_w_Ti": 1e-4, "sigma_w_Qd": 0.0, "sigma_w_Qd_d1": 0.0}
NOISE.update({f"sigma_x0_{s}": 1.0 for s in ("Ti", "Qd", "Qd_d1")})


def test_likelihood_gradient_in_the_hyper_parameters_matches_central_differences():
    """The exact gradient (complex-step state space + the diffusion's derivative) against differences of -log L."""
    net = one_node()
    data = synthetic(net, None)
    values = {**net.values(), **NOISE}
    wrt = ("sd", "ld", "R1", "Ci")
    _, g, _ = general_cost(net, values, data, "zoh", "ml", wrt)
    for k, w in enumerate(wrt):
        h = 1e-5 * values[w]
        hi = general_cost(net, {**values, w: values[w] + h}, data, "zoh", "ml")[0]
        lo = general_cost(net, {**values, w: values[w] - h}, data, "zoh", "ml")[0]
        assert g[k] == pytest.approx((hi - lo) / (2 * h), rel=1e-4, abs=1e-9 * abs(values[w]) ** -1), w


def test_zero_magnitude_gives_the_likelihood_of_the_model_without_the_disturbance():
    """Nesting at sigma = 0: the latent states no longer reach the output, -log L is the plain model's."""
    with_d = one_node(magnitude=0.0)
    plain = RCNetwork(
        "plain",
        with_d.nodes,
        with_d.boundaries,
        with_d.resistors,
        with_d.parameters.values(),
        with_d.heat_inputs,
    )
    data = synthetic(one_node(), None)
    values = {**with_d.values(), **NOISE}
    a = general_cost(with_d, values, data, "zoh", "ml")[0]
    b = general_cost(plain, {k: v for k, v in values.items() if "Qd" not in k}, data, "zoh", "ml")[0]
    assert a == pytest.approx(b, rel=1e-8)  # two discretizations (modal vs expm) agree to ~1e-12


@pytest.mark.parametrize(
    ("make", "match"),
    [
        (lambda: LatentForce("Qd", "matern12", "Ti", magnitude=1.0, length_scale=1.0), "matern32"),
        (lambda: LatentForce("Qd", "periodic", "Ti", magnitude=1.0, length_scale=1.0), "needs a period"),
        (
            lambda: LatentForce("Qd", "matern32", "Ti", magnitude=1.0, length_scale=1.0, period=9.0),
            "no period",
        ),
        (lambda: LatentForce("Q d", "matern32", "Ti", magnitude=1.0, length_scale=1.0), "identifier"),
        (lambda: LatentForce("Qd", "matern32", {}, magnitude=1.0, length_scale=1.0), "gains"),
    ],
)
def test_bad_disturbance_declarations_are_refused(make, match):
    with pytest.raises(NetworkError, match=match):
        make()


def test_bad_disturbance_in_a_network_is_refused_with_the_reason():
    base = one_node()
    d = base.disturbances[0]

    def with_(dist, params=()):
        return RCNetwork(
            "x",
            base.nodes,
            base.boundaries,
            base.resistors,
            [*base.parameters.values(), *params],
            base.heat_inputs,
            disturbances=[dist],
        )

    with pytest.raises(NetworkError, match="undeclared node 'Tx'"):
        with_(LatentForce("Qd", "matern32", "Tx", magnitude="sd", length_scale="ld"))
    with pytest.raises(NetworkError, match="declared as a resistance, not a magnitude"):
        with_(LatentForce("Qd", "matern32", "Ti", magnitude="R1", length_scale="ld"))
    with pytest.raises(NetworkError, match="reuses a node"):
        with_(LatentForce("Ti", "matern32", "Ti", magnitude="sd", length_scale="ld"))
    with pytest.raises(ParameterError, match="magnitude must be >= 0"):
        with_(LatentForce("Qd", "matern32", "Ti", magnitude=-3.0, length_scale="ld"))
    with pytest.raises(ParameterError, match="must be > 0"):
        with_(LatentForce("Qd", "matern32", "Ti", magnitude=3.0, length_scale=0.0))
    with pytest.raises(ParameterError, match="must be > 0"):
        Parameter("sd", "magnitude", 0.0)
    assert with_(d).replace_parameters([Parameter("sd", "magnitude", 5.0)]).disturbances == (d,)
