"""A fitted zone model with its noise model, for other control tools.

* :func:`to_control`: a python-control ``StateSpace`` (continuous, or discrete ZOH at a sample
  time) at a flow, with the noise model as extra inputs: unit-intensity white noise ``w_<state>``
  through ``sqrt(Qc)`` (or a square root of ``Qd`` when discrete) and unit measurement noise
  ``v_<output>`` through ``sqrt(R)``, so ``control.lqe`` / ``dlqe`` or a simulation with noise
  use the fitted covariances directly.
* :func:`named_arrays`: plain numpy arrays with names and units and the flow dependence,
  ``dx/dt = (A0 + sum_f m_f N_f) x + (B0 + sum_f m_f M_f) u + E P + w``, ``y = C x + D u + v``,
  ``w ~ Qc``, ``v ~ R``, for CasADi or do-mpc users who write the bilinear model symbolically
  (the flow ``m`` as a decision variable).

References
----------
.. [1] R. M. Murray et al., python-control, ``StateSpace`` (version 0.10).
.. [2] S. Lucia, A. Tatulea-Codrean, C. Schoppmeyer, S. Engell, "Rapid development of modular
   and sustainable nonlinear model predictive control solutions", Control Engineering Practice
   60 (2017) 51-62 (do-mpc).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from rczone.control.disturbance import Disturbance
from rczone.control.model import ControlModel
from rczone.errors import RczoneError
from rczone.models.zone import ZoneModel


def psd_sqrt(S: np.ndarray) -> np.ndarray:
    """A square root ``G`` with ``G G' = S`` of a symmetric positive semidefinite ``S`` (eigenvalues clipped at 0)."""
    lam, V = np.linalg.eigh(0.5 * (S + S.T))
    return V * np.sqrt(np.clip(lam, 0.0, None))


def to_control(
    model: ZoneModel | ControlModel,
    *,
    m: float | np.ndarray = 0.0,
    dt: float | None = None,
    noise: bool = True,
) -> Any:
    """A ``control.StateSpace`` of the model at flow ``m`` (kg/s), continuous or ZOH at ``dt`` s.

    With ``noise`` the inputs ``w_<state>`` and ``v_<output>`` (unit white noise) follow the
    model's inputs (see the module notes). Needs the extra ``rczone[control]``.
    """
    try:
        import control
    except ImportError:
        raise RczoneError(
            "python-control is not installed; install the extra: pip install 'rczone[control]'"
        ) from None
    cm = model if isinstance(model, ControlModel) else ControlModel(model)
    c = cm.matrices
    if dt is None:
        A, BE = cm.continuous(m)
        B, Gw = BE[:, : c.B0.shape[1]], psd_sqrt(c.Qc)
    else:
        d = cm.discrete(dt, m)
        A, B, Gw = d.Ad, d.Bd, psd_sqrt(d.Qd)
    ny = c.C.shape[0]
    inputs, outputs = list(cm.input_names), list(cm.output_names)
    if noise:
        B = np.hstack([B, Gw, np.zeros((A.shape[0], ny))])
        D = np.hstack([c.D, np.zeros((ny, A.shape[0])), np.sqrt(cm.noise.R)])
        inputs += [f"w_{s}" for s in cm.state_names] + [f"v_{o}" for o in outputs]
    else:
        D = c.D
    kw = {"states": list(cm.state_names), "inputs": inputs, "outputs": outputs}
    return control.ss(A, B, c.C, D, **kw) if dt is None else control.ss(A, B, c.C, D, dt, **kw)


@dataclass(frozen=True, eq=False)
class NamedArrays:
    """The bilinear model and its noise as plain arrays (see :func:`named_arrays`).

    Attributes
    ----------
    arrays : dict of str to ndarray
        ``A0`` (n, n) 1/s; ``N`` (nf, n, n) 1/kg; ``B0`` (n, p); ``M`` (nf, n, p); ``E`` (n, 1) K/J
        (heat at the supply-air node, the reheat power); ``C`` (ny, n); ``D`` (ny, p);
        ``Qc`` (n, n) K^2/s; ``R`` (ny, ny) K^2.
    names : dict of str to tuple of str
        ``states``, ``inputs``, ``flows``, ``outputs``.
    units : dict of str to str
        Every state, input, flow and output.
    """

    arrays: dict[str, np.ndarray]
    names: dict[str, tuple[str, ...]]
    units: dict[str, str]

    equation = (
        "dx/dt = (A0 + sum_f m_f N_f) x + (B0 + sum_f m_f M_f) u + E P + w,  w ~ N(0, Qc dt);"
        "  y = C x + D u + v,  v ~ N(0, R)"
    )

    def to_dict(self) -> dict[str, Any]:
        return {
            "equation": self.equation,
            "arrays": {k: v.tolist() for k, v in self.arrays.items()},
            "names": {k: list(v) for k, v in self.names.items()},
            "units": dict(self.units),
        }


def named_arrays(model: ZoneModel | ControlModel, *, disturbance: Disturbance | None = None) -> NamedArrays:
    """The model, its noise and optionally a disturbance state as :class:`NamedArrays`."""
    cm = model if isinstance(model, ControlModel) else ControlModel(model, disturbance=disturbance)
    c = cm.matrices
    net = cm.model.network
    units = {s: "degC" for s in net.state_names}
    if cm.disturbance is not None:
        units[cm.disturbance.state_name] = cm.disturbance.unit
    units.update(cm.model.signal_quantities())
    quantity_unit = {"temperature": "degC", "flow": "kg/s", "power": "W", "irradiance": "W/m2"}
    units = {k: quantity_unit.get(v, v) for k, v in units.items()}
    units["P"] = "W"
    arrays = {
        "A0": c.A0,
        "N": c.N,
        "B0": c.B0,
        "M": c.M,
        "E": c.E,
        "C": c.C,
        "D": c.D,
        "Qc": c.Qc,
        "R": cm.noise.R,
    }
    names = {
        "states": cm.state_names,
        "inputs": cm.input_names,
        "flows": cm.flow_names,
        "outputs": cm.output_names,
    }
    return NamedArrays({k: np.array(v) for k, v in arrays.items()}, names, units)
