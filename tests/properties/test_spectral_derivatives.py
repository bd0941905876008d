"""Spectral derivatives of the exact discretization against the complex step and Fréchet derivatives.

:func:`rczone.kernels.discretize.interval_derivatives` with ``scale`` (the Daleckii-Krein
route of :func:`~rczone.kernels.discretize.spectral_derivatives`) is compared with

* the complex step [1]_ through the plain matrix-exponential discretization of
  :mod:`rczone.simulation.discretize` (``scipy.linalg.expm`` block exponentials for ``Phi``,
  ``G0``, ``G1``; Van Loan with doubling for ``Qd``), exact to rounding since it has no
  subtraction, and
* the compiled matrix-exponential route of the same function (Fréchet derivatives of Van
  Loan's block exponentials, ``scale`` empty).

Models: random RC networks (massless nodes, one or two supply-air flows, resistance and
capacity directions: a capacity's ``dA`` is not symmetrized by ``diag(sqrt(c))``) and
symmetrizable state matrices built with exactly repeated and nearly repeated eigenvalues, with
random dense directions. ZOH and FOH; intervals from seconds (every eigenvalue in the series
range of the divided differences) to hours (stiff modes).

References
----------
.. [1] J. R. R. A. Martins, P. Sturdza, J. J. Alonso, "The complex-step derivative
   approximation", ACM Trans. Math. Software 29(3), 2003.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rczone.kernels.arrays import Discretization, dynamics_derivatives, dynamics_model
from rczone.kernels.discretize import interval_derivatives, rc2_interval_derivatives
from rczone.simulation import foh, zoh
from rczone.simulation.discretize import process_noise_covariance, symmetrizing_scale
from tests.netfactory import random_network

H_CS = 1e-30
RTOL = 1e-9
SETTINGS = settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def relerr(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(a - b) / max(np.linalg.norm(b), 1e-300))


def complex_step(A, B, qc, dt, hold, dA, dB, dqc) -> tuple[np.ndarray, ...]:
    """``dPhi, dG0, dG1, dQd`` along one direction by the complex step through the plain expm functions."""
    Ac, Bc, Qc = A + 1j * H_CS * dA, B + 1j * H_CS * dB, np.diag(qc + 1j * H_CS * dqc)
    if hold == "zoh":
        Phi, G0 = zoh(Ac, Bc, dt)
        G1 = np.zeros_like(G0)
    else:
        Phi, G0, G1 = foh(Ac, Bc, dt)
    Qd = process_noise_covariance(Ac, Qc, dt)
    return tuple(X.imag / H_CS for X in (Phi, G0, G1, Qd))


def both_routes(A, B, scale, qc, keys, hold, dA, dB, dqc, noise=True):
    """``interval_derivatives`` of one LTI model by the spectral route and by the expm route."""
    n, p = B.shape
    q = dA.shape[0]
    mod = dynamics_model(A, np.zeros((0, n, n)), B, np.zeros((0, n, p)), qc)
    der = dynamics_derivatives(dA, np.zeros((q, 0, n, n)), dB, np.zeros((q, 0, n, p)), dqc)
    how = Discretization(np.ascontiguousarray(keys, dtype=float), np.empty(0), hold == "foh", noise)
    spec = interval_derivatives(mod, der, how._replace(scale=scale))
    ref = interval_derivatives(mod, der, how)
    return spec, ref


def check(A, B, scale, qc, dts, hold, dA, dB, dqc) -> None:
    keys = np.asarray(dts, dtype=float)[:, None]
    (mats, dmats), (mats_x, dmats_x) = both_routes(A, B, scale, qc, keys, hold, dA, dB, dqc)
    for X, Y in zip(mats + dmats, mats_x + dmats_x):
        assert relerr(X, Y) <= RTOL
    for k, dt in enumerate(keys[:, 0]):
        for d in range(dA.shape[0]):
            ref = complex_step(A, B, qc, dt, hold, dA[d], dB[d], dqc[d])
            for dm, Y in zip(dmats, ref):
                # relative to the derivative, or to the largest of that matrix when a direction hardly moves it
                tol = RTOL * max(np.abs(Y).max(), 1e-3 * np.abs(dm[k]).max())
                assert np.abs(dm[k, d] - Y).max() <= tol


@SETTINGS
@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 5),
    st.integers(0, 2),
    st.integers(1, 2),
    st.sampled_from(["zoh", "foh"]),
)
def test_spectral_derivatives_of_rc_networks_equal_the_complex_step(seed, n_cap, n_massless, n_flows, hold):
    rng = np.random.default_rng(seed)
    net = random_network(rng, n_cap, n_massless, 2, n_flows=n_flows)
    theta = net.values()
    ss = net.state_space(theta)
    scale = symmetrizing_scale(ss.A, ss.N, ss.capacities)
    assert scale is not None
    m = rng.uniform(0.0, 0.4, n_flows)
    A, B = ss.matrices(m)
    names = list(net.free_parameter_names)
    ders = net.state_space_derivatives(theta, names, log=False)
    n, p = B.shape
    q = len(names) + 1
    dA, dB, dqc = np.zeros((q, n, n)), np.zeros((q, n, p)), np.zeros((q, n))
    for k, d in enumerate(ders):
        dA[k] = d.dA + np.tensordot(m, d.dN, axes=1)
        dB[k] = d.dB + np.tensordot(m, d.dM, axes=1)
    dqc[-1] = rng.uniform(0.0, 1.0, n)  # a process-noise direction
    assert any(n.startswith("C") for n in names)  # capacity directions are included
    qc = rng.uniform(1e-4, 1e-2, n)
    check(A, B, scale, qc, [1.0, 60.0, 3600.0], hold, dA, dB, dqc)


def symmetrizable(rng: np.random.Generator, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``A = D^-1 Q diag(lam) Q' D`` for a random orthogonal ``Q`` and positive diagonal ``D``: its scale."""
    n = lam.size
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    scale = np.exp(rng.uniform(-2.0, 2.0, n))
    S = Q @ np.diag(lam) @ Q.T
    return S * (1.0 / scale)[:, None] * scale[None, :], scale


@pytest.mark.parametrize("hold", ["zoh", "foh"])
@pytest.mark.parametrize(
    "lam",
    [
        [-1e-3, -1e-3, -1e-3, -0.2],  # exactly repeated (a triple eigenvalue)
        [-1e-3, -1e-3 * (1 + 1e-9), -0.05, -0.05 * (1 + 1e-7)],  # nearly repeated pairs
        [-1e-3, -1e-3 * (1 + 1e-4), -0.02, -0.0201, 0.0],  # close, and a zero eigenvalue
        [-5.0, -5.0 * (1 + 1e-6), -1e-4, -2.0],  # stiff and nearly repeated
    ],
)
def test_spectral_derivatives_with_repeated_eigenvalues_equal_the_complex_step(lam, hold):
    rng = np.random.default_rng(len(lam) + int(1e6 * abs(lam[1])))
    A, scale = symmetrizable(rng, np.array(lam))
    n, p, q = A.shape[0], 3, 4
    B = rng.standard_normal((n, p))
    # dense directions of every kind: not symmetrized by the scale, like a capacity's
    dA = rng.standard_normal((q, n, n)) * np.abs(A).max()
    dB = rng.standard_normal((q, n, p))
    dqc = rng.uniform(0.0, 1.0, (q, n))
    dA[1], dB[2], dqc[0] = 0.0, 0.0, 0.0
    qc = rng.uniform(0.1, 1.0, n)
    check(A, B, scale, qc, [0.5, 60.0, 900.0], hold, dA, dB, dqc)


def test_spectral_derivatives_without_noise_or_directions():
    """Least squares (no ``Qd``) and no directions: the matrices still equal the expm route."""
    rng = np.random.default_rng(7)
    A, scale = symmetrizable(rng, np.array([-1e-3, -2e-2, -0.3]))
    B = rng.standard_normal((3, 2))
    keys = np.array([[60.0], [600.0]])
    for q in (0, 2):
        dA = rng.standard_normal((q, 3, 3))
        dB, dqc = rng.standard_normal((q, 3, 2)), rng.uniform(0, 1, (q, 3))
        (mats, dmats), (mats_x, dmats_x) = both_routes(
            A, B, scale, np.ones(3), keys, "foh", dA, dB, dqc, False
        )
        for X, Y in zip(mats + dmats, mats_x + dmats_x):
            assert X.shape == Y.shape
            assert relerr(X, Y) <= RTOL or np.abs(Y).max() == 0.0 == np.abs(X).max()
        assert not np.any(mats[3]) and not np.any(dmats[3])


def check_two_states(A, B, scale, qc, dts, hold, dA, dB, dqc, noise=True) -> None:
    """The written-out 2-state route against the matrix-exponential route and the complex step."""
    n, p = B.shape
    q = dA.shape[0]
    keys = np.asarray(dts, dtype=float)[:, None]
    mod = dynamics_model(A, np.zeros((0, n, n)), B, np.zeros((0, n, p)), qc)
    der = dynamics_derivatives(dA, np.zeros((q, 0, n, n)), dB, np.zeros((q, 0, n, p)), dqc)
    how = Discretization(np.ascontiguousarray(keys), scale, hold == "foh", noise)
    mats, dmats = rc2_interval_derivatives(mod, der, how)
    assert np.array_equal(interval_derivatives(mod, der, how)[1].dPhi, dmats.dPhi)  # the RC route takes it
    mats_x, dmats_x = interval_derivatives(mod, der, how._replace(scale=np.empty(0)))
    for X, Y in zip(mats + dmats, mats_x + dmats_x):
        assert X.shape == Y.shape
        assert relerr(X, Y) <= RTOL or np.abs(Y).max() == 0.0 == np.abs(X).max()
    if not noise:
        return
    for k, dt in enumerate(keys[:, 0]):
        for d in range(q):
            ref = complex_step(A, B, qc, dt, hold, dA[d], dB[d], dqc[d])
            for dm, Y in zip(dmats, ref):
                tol = RTOL * max(np.abs(Y).max(), 1e-3 * np.abs(dm[k]).max())
                assert np.abs(dm[k, d] - Y).max() <= tol


@SETTINGS
@given(st.integers(0, 2**32 - 1), st.integers(1, 2), st.sampled_from(["zoh", "foh"]), st.booleans())
def test_two_state_derivatives_of_rc_networks_equal_the_complex_step(seed, n_flows, hold, noise):
    rng = np.random.default_rng(seed)
    net = random_network(rng, 2, 0, 2, n_flows=n_flows)
    theta = net.values()
    ss = net.state_space(theta)
    scale = symmetrizing_scale(ss.A, ss.N, ss.capacities)
    m = rng.uniform(0.0, 0.4, n_flows)
    A, B = ss.matrices(m)
    assert A.shape == (2, 2)
    names = list(net.free_parameter_names)
    ders = net.state_space_derivatives(theta, names, log=False)
    q = len(names) + 2
    dA, dB, dqc = np.zeros((q, 2, 2)), np.zeros((q, 2, B.shape[1])), np.zeros((q, 2))
    for k, d in enumerate(ders):
        dA[k] = d.dA + np.tensordot(m, d.dN, axes=1)
        dB[k] = d.dB + np.tensordot(m, d.dM, axes=1)
    dqc[-2] = rng.uniform(0.0, 1.0, 2)  # a process-noise direction; the last moves nothing
    qc = rng.uniform(1e-4, 1e-2, 2)
    check_two_states(A, B, scale, qc, [1.0, 60.0, 3600.0], hold, dA, dB, dqc, noise)


@pytest.mark.parametrize("hold", ["zoh", "foh"])
@pytest.mark.parametrize(
    "lam",
    [
        [-1e-3, -1e-3],  # exactly repeated: the rotation is the identity
        [-1e-3, -1e-3 * (1 + 1e-9)],  # nearly repeated
        [-0.02, 0.0],  # a zero eigenvalue
        [-5.0, -1e-4],  # stiff
        [-5.0, -5.0 * (1 + 1e-6)],  # stiff and nearly repeated
    ],
)
def test_two_state_derivatives_with_repeated_eigenvalues_equal_the_complex_step(lam, hold):
    rng = np.random.default_rng(int(1e6 * abs(lam[1])) + 3)
    A, scale = symmetrizable(rng, np.array(lam))
    p, q = 3, 4
    B = rng.standard_normal((2, p))
    dA = rng.standard_normal((q, 2, 2)) * np.abs(A).max()
    dB = rng.standard_normal((q, 2, p))
    dqc = rng.uniform(0.0, 1.0, (q, 2))
    dA[1], dB[2], dqc[0] = 0.0, 0.0, 0.0
    qc = rng.uniform(0.1, 1.0, 2)
    check_two_states(A, B, scale, qc, [0.5, 60.0, 900.0], hold, dA, dB, dqc)
    # a diagonal matrix (b = 0, the rotation skipped), in either order of its eigenvalues
    for diag in ([-1e-3, -0.2], [-0.2, -1e-3]):
        check_two_states(np.diag(diag), B, np.ones(2), qc, [60.0], hold, dA, dB, dqc)
