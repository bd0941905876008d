"""VDI 6007-1 test cases for the two-element reduced-order zone model, built as rczone networks.

VDI 6007-1 defines test cases for reduced-order room models; IBPSA's Modelica library
implements them with its ``ThermalZones.ReducedOrder.RC.TwoElements`` model and publishes the
guideline's reference values and its own Dymola trajectories (BSD licence; see
``data/vdi6007/PROVENANCE.md``). Here each case is the same thermal network declared with
:class:`rczone.network.RCNetwork`:

* outdoor (or equivalent) temperature ``To`` -- ``1/hConWall`` -- outer wall surface (massless)
  -- ``RExtRem`` -- exterior-wall capacity ``CExt`` -- ``RExt`` -- inner exterior-wall surface
  (massless);
* inner exterior-wall surface -- ``1/(hConExt AExt)`` -- room air (massless, or ``VAir rho cp``);
* inner exterior-wall surface -- ``1/(hRad min(AExt, AInt))`` -- inner interior-wall surface;
* inner interior-wall surface -- ``1/(hConInt AInt)`` -- room air;
* inner interior-wall surface -- ``RInt`` -- interior-wall capacity ``CInt`` (adiabatic beyond);
* convective gains into the air; radiative internal gains split over the two inner surfaces
  by area; solar gains through the windows (``gWin ATransparent solRad``, a sun blind with
  ``g = 0.15`` above 100 W/m2) 9 % convective and the rest radiative onto the surfaces not
  facing the window's own orientation (the interior wall, as IBPSA's ``splitFacVal``);
* TC10: the exterior element sees an equivalent temperature ``wfGro TGro + (1 - wfGro) To``
  (floor on an adjacent room at 15 degC);
* TC12: outdoor air ventilated into an air volume of 0.1 m3 (supply air ``m cp (To - Tair)``
  with ``m`` from the table).

Every input table is piecewise constant with steps on the hour, so the hourly means that the
guideline checks are computed exactly: the state is stepped hour by hour with the matrix
exponential of the system augmented by an integrator of the air temperature.

References
----------
.. [1] VDI 6007-1:2015, *Calculation of transient thermal response of rooms and buildings --
   Modelling of rooms*, Beuth, 2015.
.. [2] IBPSA Modelica Library, ``IBPSA.ThermalZones.ReducedOrder.Validation.VDI6007``, commit
   bad7edb9696d7a88fc41627ad74a4a2d0d9f6dde.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from importlib import resources

import numpy as np
import pandas as pd

from rczone.errors import ParameterError, did_you_mean
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir
from rczone.simulation.discretize import zoh_with_mean

#: Cases implemented; each maps to its parameter set and inputs below.
CASES = ("TC1", "TC2", "TC3", "TC4", "TC5", "TC10", "TC12")
#: Tolerances of the guideline (hourly means, K) and of the comparison with IBPSA's Dymola run.
TOL_VDI_K = 0.15
TOL_DYMOLA_K = 0.01
DAY = 86400.0
HOURS = 60 * 24
#: Air of IBPSA's media (``IBPSA.Media.Air``): density, kg/m3, and specific heat, J/(kg K).
RHO_AIR, CP_AIR = 1.2, 1006.0
#: TC12 ventilation table unit to kg/s (IBPSA TestCase12).
VENT_TO_KG_S = 0.000330375898

ROOM_S = {
    "RExt": 0.00436791293674,
    "CExt": 1600848.94,
    "RExtRem": 0.03895919557,
    "RInt": 0.000595693407511,
    "CInt": 14836354.6282,
    "AExt": 10.5,
    "AInt": 75.5,
    "hConExt": 2.7,
    "hConInt": 2.24,
    "hRad": 5.0,
    "hConWall": 25.0 * 10.5,
    "T0": 22.0,
}
ROOM_L = {
    **ROOM_S,
    "RExt": 0.00404935160802,
    "CExt": 47900.0,
    "RExtRem": 0.039330865,
    "RInt": 0.003237138,
    "CInt": 7297100.0,
}
ROOM_TC10 = {
    "RExt": 0.00171957697767797,
    "CExt": 4338751.41,
    "RExtRem": 0.011638548,
    "RInt": 0.000779671554640369,
    "CInt": 12333949.4129606,
    "AExt": 28.0,
    "AInt": 58.0,
    "hConExt": 2.4,
    "hConInt": 2.398,
    "hRad": 5.0,
    "hConWall": 28.0 * 9.75,
    "T0": 17.6,
}


@dataclass(frozen=True)
class CaseSpec:
    """What distinguishes one test case."""

    room: dict
    gains: str  # "conv": one convective column; "rad": one radiative column; "three": rad, conv, conv
    outdoor: bool = False  # outdoor temperature table (else constant T0)
    solar: bool = False
    ground_weight: float = 0.0  # TC10: equivalent temperature wfGro TGro + (1 - wfGro) To
    ground_temperature: float = 15.0
    ventilation: bool = False


SPECS = {
    "TC1": CaseSpec(ROOM_S, "conv"),
    "TC2": CaseSpec(ROOM_S, "rad"),
    "TC3": CaseSpec(ROOM_L, "conv"),
    "TC4": CaseSpec(ROOM_L, "rad"),
    "TC5": CaseSpec(ROOM_S, "three", outdoor=True, solar=True),
    "TC10": CaseSpec(ROOM_TC10, "three", outdoor=True, solar=True, ground_weight=0.629),
    "TC12": CaseSpec(ROOM_S, "three", outdoor=True, solar=True, ventilation=True),
}


@dataclass(frozen=True)
class CaseResult:
    """Deviations of one case from the references.

    Attributes
    ----------
    name : str
    max_dev_vdi_K : float
        Largest |hourly mean - VDI reference| over hours 1-24 of days 1, 10 and 60.
    max_dev_dymola_K : float
        Largest |hourly mean - IBPSA Dymola mean.y| at its sample times (those not on an hour
        boundary, where the sampled mean jumps).
    per_day : dict
        Largest VDI deviation per reference day.
    hourly_mean : ndarray, shape (1440,)
        Hourly means of the air temperature, degC (hour ending at 1 h, 2 h, ...).
    """

    name: str
    max_dev_vdi_K: float
    max_dev_dymola_K: float
    per_day: dict = field(default_factory=dict)
    hourly_mean: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)

    @property
    def passed(self) -> bool:
        return self.max_dev_vdi_K <= TOL_VDI_K and self.max_dev_dymola_K <= TOL_DYMOLA_K

    def to_dict(self) -> dict:
        return {
            "max_dev_vdi_K": self.max_dev_vdi_K,
            "max_dev_dymola_K": self.max_dev_dymola_K,
            "per_day_vdi_K": self.per_day,
            "pass": self.passed,
        }


def _table(case: str, name: str) -> pd.DataFrame:
    path = resources.files("rczone.reference") / "data" / "vdi6007" / f"TestCase{case[2:]}_{name}.csv"
    with resources.as_file(path) as p:
        return pd.read_csv(p)


def hourly_values(table: pd.DataFrame, column: str = "col2") -> np.ndarray:
    """Value of a periodic daily step table during each hour of a day, shape (24,).

    The tables repeat a time stamp at every step, so the value over ``[h, h + 1)`` is the
    table's value just after ``h`` (the last row at time ``h``).
    """
    t = table["time_s"].to_numpy(float)
    v = table[column].to_numpy(float)
    out = np.empty(24)
    for h in range(24):
        mid = h * 3600.0 + 1800.0
        i = np.searchsorted(t, mid, side="right") - 1
        j = min(i + 1, t.size - 1)
        # linear interpolation of the table at mid-hour (exact for steps on the hour)
        out[h] = v[i] if t[j] == t[i] else v[i] + (v[j] - v[i]) * (mid - t[i]) / (t[j] - t[i])
    return out


def network(spec: CaseSpec) -> RCNetwork:
    """The two-element zone of ``spec`` as an RC network.

    Inputs: ``To`` (outdoor or equivalent temperature at the exterior element), ``Tvent``
    (temperature of ventilation air), heat inputs ``Qconv`` (to the air), ``Qrad`` (radiative,
    split by area), ``Qsol`` (solar radiative, onto the interior wall); flow ``m`` (ventilation,
    TC12 only). Output ``Tair``.
    """
    r = spec.room
    a_ext, a_int = r["AExt"], r["AInt"]
    air_cap = "Cair" if spec.ventilation else None
    params = [
        Parameter("RExt", "resistance", r["RExt"]),
        Parameter("RExtRem", "resistance", r["RExtRem"]),
        Parameter("RInt", "resistance", r["RInt"]),
        Parameter("CExt", "capacitance", r["CExt"]),
        Parameter("CInt", "capacitance", r["CInt"]),
        Parameter("RConWall", "resistance", 1.0 / r["hConWall"]),
        Parameter("RConExt", "resistance", 1.0 / (r["hConExt"] * a_ext)),
        Parameter("RConInt", "resistance", 1.0 / (r["hConInt"] * a_int)),
        Parameter("RRad", "resistance", 1.0 / (r["hRad"] * min(a_ext, a_int))),
    ]
    if spec.ventilation:
        params.append(Parameter("Cair", "capacitance", 0.1 * RHO_AIR * CP_AIR))
    share_ext = a_ext / (a_ext + a_int)
    return RCNetwork(
        "VDI 6007 two-element zone",
        nodes=[
            Node("Tair", air_cap),
            Node("TextOut", None),
            Node("TExt", "CExt"),
            Node("TextIn", None),
            Node("TintIn", None),
            Node("TInt", "CInt"),
        ],
        boundaries=["To"],
        resistors=[
            Resistor("To", "TextOut", "RConWall"),
            Resistor("TextOut", "TExt", "RExtRem"),
            Resistor("TExt", "TextIn", "RExt"),
            Resistor("TextIn", "Tair", "RConExt"),
            Resistor("TextIn", "TintIn", "RRad"),
            Resistor("TintIn", "Tair", "RConInt"),
            Resistor("TintIn", "TInt", "RInt"),
        ],
        parameters=params,
        heat_inputs=[
            HeatInput("Qconv", {"Tair": 1.0}),
            HeatInput("Qrad", {"TextIn": share_ext, "TintIn": 1.0 - share_ext}),
            HeatInput("Qsol", {"TintIn": 1.0}),
        ],
        supply_air=[SupplyAir("Tair", flow="m", temperature="Tvent", cp=CP_AIR)] if spec.ventilation else [],
        outputs=["Tair"],
    )


def inputs(case: str) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Hourly inputs of one day ``(u (24, p), m (24,), input_names)`` in the network's order."""
    spec = SPECS[case]
    net = network(spec)
    gains = _table(case, "intGai")
    if spec.gains == "three":
        q_rad = hourly_values(gains, "col2")
        q_conv = hourly_values(gains, "col3") + hourly_values(gains, "col4")
    elif spec.gains == "rad":
        q_rad, q_conv = hourly_values(gains), np.zeros(24)
    else:
        q_rad, q_conv = np.zeros(24), hourly_values(gains)
    t_out = (
        hourly_values(_table(case, "outdoorTemp")) - 273.15 if spec.outdoor else np.full(24, spec.room["T0"])
    )
    t_eq = spec.ground_weight * spec.ground_temperature + (1.0 - spec.ground_weight) * t_out
    q_sol = np.zeros(24)
    if spec.solar:
        rad = hourly_values(_table(case, "tableSolRadWindow"))
        q_sol = rad * np.where(rad > 100.0, 0.15, 1.0) * 1.0 * 7.0  # g_sunblind, gWin, ATransparent
    m = hourly_values(_table(case, "ventRate")) * VENT_TO_KG_S if spec.ventilation else np.zeros(24)
    cols = {"To": t_eq, "Tvent": t_out, "Qconv": q_conv + 0.09 * q_sol, "Qrad": q_rad, "Qsol": 0.91 * q_sol}
    names = net.state_space().input_names
    return np.column_stack([cols[n] for n in names]), m, names


def hourly_means(case: str) -> np.ndarray:
    """Exact hourly means of the air temperature over 60 days, degC, shape (1440,)."""
    spec = SPECS[case]
    ss = network(spec).state_space()
    u_day, m_day, _ = inputs(case)
    x = np.full(ss.n_states, spec.room["T0"])
    # one exact step per hour and the exact mean of the state over it (rczone.simulation.discretize)
    steps = {}
    for mk in np.unique(m_day):
        A, B = ss.matrices(mk) if ss.n_flows else (ss.A, ss.B)
        steps[mk] = zoh_with_mean(A, B, 3600.0)
    out = np.empty(HOURS)
    for k in range(HOURS):
        h = k % 24
        step = steps[m_day[h]]
        mean = step.Psi @ x + step.Lambda @ u_day[h]
        x = step.Phi @ x + step.Gamma @ u_day[h]
        out[k] = (ss.C @ mean)[0] + (ss.D @ u_day[h])[0]
    return out


REFERENCE_DAYS = {"day 1": 0, "day 10": 9, "day 60": 59}


def deviations(case: str, means: np.ndarray, reference: pd.DataFrame, dymola: pd.DataFrame) -> CaseResult:
    """Compare hourly means with the VDI reference table and IBPSA's Dymola trajectory."""
    t_ref = reference["time_s"].to_numpy(float)
    v_ref = reference["col2"].to_numpy(float)
    per_day = {}
    for label, d in REFERENCE_DAYS.items():
        devs = []
        for h in range(1, 25):
            t = d * DAY + h * 3600.0
            i = np.flatnonzero(np.isclose(t_ref, t))
            if i.size:
                devs.append(abs(means[d * 24 + h - 1] - v_ref[i[-1]]))
        per_day[label] = float(max(devs))
    td = dymola["time_s"].to_numpy(float)
    yd = dymola["mean_y"].to_numpy(float) - 273.15
    keep = (td > 3600.0) & (np.mod(td, 3600.0) != 0.0)
    idx = (td[keep] // 3600.0).astype(int) - 1  # the mean over the last completed hour
    dev_dym = float(np.max(np.abs(means[idx] - yd[keep])))
    return CaseResult(case, max(per_day.values()), dev_dym, per_day, means)


def run_case(name: str) -> CaseResult:
    """Simulate one test case and compare it with both references."""
    if name not in SPECS:
        raise ParameterError(
            f"unknown VDI 6007 test case {name!r}; "
            + did_you_mean(name, CASES)
            + f" (cases: {', '.join(CASES)})"
        )
    return deviations(
        name, hourly_means(name), _table(name, "reference"), _table(name, "dymola_regression_meany")
    )


def run_all(cases: list[str] | tuple[str, ...] | None = None) -> dict[str, CaseResult]:
    """Run the given cases (default all) in order."""
    return {c: run_case(c) for c in (cases or CASES)}
