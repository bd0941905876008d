"""Building-management-system sensors of the virtual building.

As a BMS trend log has them: 1-minute samples;

* temperatures (zone air, outdoor, discharge): Gaussian noise with standard deviation
  ``TEMP_NOISE`` = 0.05 K (thermistor with 10-bit transmitter), then quantized to 0.1 F
  (BMS trend resolution; the paper's plots are in F) and converted back to degC;
* supply air flow: Gaussian noise of ``FLOW_NOISE`` = 0.002 kg/s (a VAV velocity-pressure
  sensor is good to a few % of its 0.12 kg/s span), clipped at zero, quantized to
  ``FLOW_QUANT`` = 0.001 kg/s.
"""

from __future__ import annotations

import numpy as np

#: Temperature sensor noise standard deviation, K.
TEMP_NOISE = 0.05
#: Trend-log temperature resolution, F.
TEMP_QUANT_F = 0.1
#: Flow sensor noise standard deviation, kg/s.
FLOW_NOISE = 0.002
#: Flow resolution, kg/s.
FLOW_QUANT = 0.001


def quantize_f(t_c: np.ndarray, step_f: float = TEMP_QUANT_F) -> np.ndarray:
    """Round degC values to a grid of ``step_f`` F and return degC."""
    f = np.asarray(t_c, dtype=float) * 1.8 + 32.0
    return (np.round(f / step_f) * step_f - 32.0) / 1.8


def sense_temperature(
    t_c: np.ndarray, rng: np.random.Generator, noise: float = TEMP_NOISE, step_f: float = TEMP_QUANT_F
) -> np.ndarray:
    """Noisy reading of true temperatures ``t_c`` (degC), quantized to ``step_f`` F."""
    t_c = np.asarray(t_c, dtype=float)
    return quantize_f(t_c + rng.normal(0.0, noise, size=t_c.shape), step_f)


def sense_flow(m: np.ndarray, rng: np.random.Generator, noise: float = FLOW_NOISE) -> np.ndarray:
    """Noisy, quantized reading of true flows ``m`` (kg/s)."""
    m = np.asarray(m, dtype=float)
    r = np.clip(m + rng.normal(0.0, noise, size=m.shape), 0.0, None)
    return np.round(r / FLOW_QUANT) * FLOW_QUANT
