"""The paper's questions in closed loop, as one paired comparison (``rczone control-test --study paper``).

The paper asks (Q1) whether a reduced model (2 states, 1 state) controls as well as the full
13-state model of the zone, and (Q2) whether a model fitted on closed-loop data is as good for
control as one fitted on a forced-response experiment. Both are answered here as the MPC's
closed-loop scores on the virtual building, every entry on the same seeds and limits, each with a
paired difference to the entry it answers against:

* Q1: the MPC with the 13-state construction model (the reference), with the 2-state model of
  the paper and with the 1-state model aggregated from the full one;
* Q2: the MPC with the paper's 2-state model fitted by maximum likelihood on the forced night C
  and on the closed-loop night A of the virtual building (:mod:`rczone.datasets`), the latter
  paired against the former.

The commissioned thermostat runs beside them as the baseline, paired against the 13-state MPC.
Every MPC estimates an unmeasured heat input (the disturbance state) but one: the 2-state MPC
without it, paired against the same model with it, the independent review of issue 33's third
finding (without it every model failed alike).
"""

from __future__ import annotations

from collections.abc import Callable

from rczone.control.comparison import Entry
from rczone.errors import ParameterError, did_you_mean
from rczone.models import load_model
from rczone.models.zone import ZoneModel

#: The studies ``--study`` knows.
STUDIES = ("paper",)
#: The reference entry of the paper study.
REFERENCE = "Q1 13-state"
#: The entry without the disturbance state.
NO_DISTURBANCE = "2-state, no disturbance estimate"


def fitted(name: str, night: str) -> ZoneModel:
    """``name`` fitted by ML on the virtual building's night ``night`` (one start from the construction values)."""
    from rczone import datasets
    from rczone.calibration import calibrate

    return calibrate(name, datasets.load(night), method="ml", n_starts=1, uncertainty=False).model


def paper_entries(fit: Callable[[str, str], ZoneModel] = fitted) -> list[Entry]:
    """The entries of the paper study (module notes); ``fit(model, night)`` makes the Q2 models."""
    forced = "Q2 2-state, ML on C (forced)"
    return [
        Entry(REFERENCE, "mpc", load_model("full-scale")),
        Entry("Q1 2-state", "mpc", load_model("second-order-paper")),
        Entry("Q1 1-state", "mpc", load_model("first-order")),
        Entry(forced, "mpc", fit("second-order-paper", "C")),
        Entry("Q2 2-state, ML on A (closed loop)", "mpc", fit("second-order-paper", "A"), reference=forced),
        Entry(
            NO_DISTURBANCE, "mpc", load_model("second-order-paper"), disturbance=False, reference="Q1 2-state"
        ),
        Entry("baseline: thermostat", "thermostat"),
    ]


def study_entries(name: str) -> list[Entry]:
    """The entries of study ``name`` (:data:`STUDIES`)."""
    if name not in STUDIES:
        raise ParameterError(f"unknown study {name!r}; " + did_you_mean(str(name), STUDIES))
    return paper_entries()
