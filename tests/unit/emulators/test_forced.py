"""The forced test's set points: rczone design's schedule, within the range, held at least an hour."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("pyenergyplus")

from rczone.diagnostics.design import actuatable
from rczone.emulators.energyplus import EnergyPlusEmulator
from rczone.emulators.forced import HOLD_S, SETPOINTS, design_setpoints, forced_run, thermostat_model
from rczone.errors import ParameterError


def test_the_set_point_is_an_input_a_test_can_drive():
    net = thermostat_model()
    assert "Tset" in actuatable(net) and net.flow_names == ("Kt",)


def test_the_designed_set_points_span_the_range_with_hour_long_holds():
    em = EnergyPlusEmulator("office_small", "usa_il_chicago", start="03-01", days=1, step_minutes=15)
    sp = design_setpoints(em)
    assert sp.shape == (97,) and sp.min() == SETPOINTS[0] and sp.max() == SETPOINTS[1]
    changes = np.flatnonzero(np.diff(sp)) + 1
    holds = np.diff(np.concatenate([[0], changes]))
    assert holds.min() * em.step_s >= HOLD_S


@pytest.mark.parametrize(
    "zones, days, match",
    [
        ("Attic", 1, "has no air terminal"),
        ("Core_ZN", 8, "at most 7 days"),
        ("nowhere", 1, "no zone 'nowhere'"),
    ],
)
def test_a_forced_test_it_cannot_run_is_refused_before_energyplus_starts(zones, days, match):
    em = EnergyPlusEmulator("office_small", "usa_il_chicago", start="03-01", days=days, step_minutes=15)
    with pytest.raises(ParameterError, match=match):
        forced_run(em, zones)
