"""Discretization and exact simulation."""

from rczone.simulation.discretize import foh, van_loan, zoh
from rczone.simulation.simulate import SimulationResult, simulate, steady_state

__all__ = ["SimulationResult", "foh", "simulate", "steady_state", "van_loan", "zoh"]
