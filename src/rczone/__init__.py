"""rczone: control-oriented grey-box RC thermal models of building zones.

Declare an RC network, build its bilinear state space, simulate it exactly, compare
model orders, and identify R and C from data::

    import rczone
    model = rczone.load_model("TiTe+heater")
    fitted = rczone.fit(model, "trend.csv", columns="map.toml")
    print(fitted.summary())

The names below are imported on first use, so ``import rczone`` stays fast (no numerical
kernel is compiled until a computation needs it).
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

#: Exported name -> the module that defines it.
_EXPORTS = {
    # the network and its parameters
    "RCNetwork": "rczone.network",
    "Node": "rczone.network",
    "Resistor": "rczone.network",
    "HeatInput": "rczone.network",
    "SupplyAir": "rczone.network",
    "LatentForce": "rczone.network",
    "Parameter": "rczone.network",
    # models
    "ZoneModel": "rczone.models",
    "load_model": "rczone.models",
    "model_to_toml": "rczone.models",
    # data, fit, predict
    "load_data": "rczone.workflow.api",
    "fit": "rczone.workflow.api",
    "predict": "rczone.workflow.api",
    "score_horizons": "rczone.workflow.api",
    "FitSettings": "rczone.estimation.settings",
    "TrendLog": "rczone.workflow.datasource",
    "BuiltinNight": "rczone.workflow.datasource",
    "VirtualNight": "rczone.workflow.datasource",
    "simulate": "rczone.workflow.api",
    "diagnose": "rczone.workflow.api",
    "design_test": "rczone.workflow.api",
    "select_models": "rczone.workflow.api",
    "smooth": "rczone.workflow.smoothing",
    # plug-ins: estimation methods (rczone.methods entry points)
    "Method": "rczone.estimation.methods",
    "MethodOptions": "rczone.estimation.methods",
    "FitProblem": "rczone.estimation.methods",
    "register_method": "rczone.estimation.methods",
    "method_names": "rczone.estimation.methods",
    # plug-ins: controllers and emulators (rczone.controllers, rczone.emulators entry points)
    "register_controller": "rczone.control.registry",
    "register_emulator": "rczone.emulators.registry",
    # results
    "Calibration": "rczone.calibration",
    "Prediction": "rczone.calibration",
    "SmoothedStates": "rczone.estimation.smoother",
    "FitResult": "rczone.estimation.result",
    "Estimate": "rczone.results",
    "Verdict": "rczone.results.verdict",
    "IdentifiabilityReport": "rczone.diagnostics",
    "Selection": "rczone.selection",
    # errors
    "RczoneError": "rczone.errors",
    "DataError": "rczone.errors",
    "ParameterError": "rczone.errors",
}

__all__ = ["__version__", *_EXPORTS]


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'rczone' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_EXPORTS})
