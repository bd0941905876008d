"""Diagnostics: can these data identify these parameters? And a test design that can."""

from rczone.diagnostics.identifiability import IdentifiabilityReport, ParameterVerdict, diagnose
from rczone.diagnostics.indicators import DataIndicators, data_indicators

__all__ = ["DataIndicators", "IdentifiabilityReport", "ParameterVerdict", "data_indicators", "diagnose"]
