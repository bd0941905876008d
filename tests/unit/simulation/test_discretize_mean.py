"""The mean of the state over a zero-order-hold step, against quadrature of the exact solution."""

import numpy as np
import pytest
from scipy.integrate import quad_vec
from scipy.linalg import expm

from rczone.simulation.discretize import zoh, zoh_with_mean


@pytest.mark.parametrize("dt", [60.0, 3600.0, 86400.0])
def test_mean_over_a_step_equals_the_integral_of_the_exact_solution(dt):
    # a two-node RC room (air and wall) with outdoor temperature and heat as inputs
    A = np.array([[-1 / 2e3 - 1 / 5e3, 1 / 5e3], [1 / 5e4, -1 / 5e4 - 1 / 2e5]])
    B = np.array([[1 / 2e3, 1e-6], [1 / 2e5, 0.0]])
    x0, u = np.array([21.0, 15.0]), np.array([-5.0, 800.0])
    step = zoh_with_mean(A, B, dt)

    def x(s):  # x(s) = e^{As} x0 + int_0^s e^{Ar} dr B u, the latter from the ZOH pair at s
        phi, gamma = zoh(A, B, s) if s > 0 else (np.eye(2), np.zeros((2, 2)))
        return phi @ x0 + gamma @ u

    mean, _ = quad_vec(x, 0.0, dt, epsabs=1e-12, epsrel=1e-12)
    np.testing.assert_allclose(step.Psi @ x0 + step.Lambda @ u, mean / dt, rtol=1e-9)
    np.testing.assert_allclose(step.Phi, expm(A * dt), rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(step.Phi @ x0 + step.Gamma @ u, x(dt), rtol=1e-10, atol=1e-9)  # K
