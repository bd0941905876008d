"""One settings object for a fit, shared by ``rczone fit``, the Python API and the checks after a fit.

The command line's options and :func:`rczone.fit`'s keywords build the same :class:`FitSettings`,
so their defaults cannot drift apart (they did: the API defaulted to least squares while the
command line defaulted to maximum likelihood).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from rczone.errors import ParameterError
from rczone.estimation.methods import DEFAULT_METHOD, method_of
from rczone.estimation.optimize import OPTIMIZERS
from rczone.estimation.sampling import SamplerSettings

#: Process-noise placements of an ML or MAP fit (:func:`rczone.estimation.fit.default_free`).
NOISE_PLACEMENTS = ("measured", "all")


@dataclass(frozen=True)
class FitSettings:
    """How to fit: method, free parameters, search, and the checks after the fit.

    Attributes
    ----------
    method : str
        A method of :data:`rczone.estimation.methods.REGISTRY`; default ``"ml"``.
    free : tuple of str or None
        Free parameters; None for :func:`rczone.estimation.fit.default_free`.
    optimizer : str
        ``"auto"`` or one of :data:`rczone.estimation.optimize.OPTIMIZERS`.
    n_starts : int or None
        Local searches; None for the global search, 1 for one local search.
    seed : int
        Seed of the global search.
    noise : {"measured", "all"}
        ML and MAP: process noise on the measured states or on every state.
    constants : dict of str to float
        Inputs held constant instead of read from the data, SI units.
    checks : bool
        Make the checks after the fit (identifiability at the estimates, profiles, other data);
        the command line makes them when it writes JSON or a report.
    profiles : bool
        With ``checks``: profile each R and C over a factor of 10 (single-output models).
    sampler : SamplerSettings
        Draws, warm-up and chains of a sampling method (``"mcmc"``); the seed is :attr:`seed`.
    """

    method: str = DEFAULT_METHOD
    free: tuple[str, ...] | None = None
    optimizer: str = "auto"
    n_starts: int | None = None
    seed: int = 0
    noise: str = "measured"
    constants: Mapping[str, float] = field(default_factory=dict)
    checks: bool = True
    profiles: bool = True
    sampler: SamplerSettings = field(default_factory=SamplerSettings)

    def __post_init__(self) -> None:
        method_of(self.method)
        if self.optimizer != "auto" and self.optimizer not in OPTIMIZERS:
            raise ParameterError(
                f"optimizer must be 'auto' or one of {', '.join(OPTIMIZERS)}, got {self.optimizer!r}"
            )
        if self.noise not in NOISE_PLACEMENTS:
            raise ParameterError(f"noise must be one of {', '.join(NOISE_PLACEMENTS)}, got {self.noise!r}")
        if self.n_starts is not None and (
            isinstance(self.n_starts, bool) or not isinstance(self.n_starts, int) or self.n_starts < 1
        ):
            raise ParameterError(
                f"n_starts must be None (automatic) or a positive integer, got {self.n_starts!r}"
            )
        if isinstance(self.seed, bool) or not isinstance(self.seed, int):
            raise ParameterError(f"seed must be an integer, got {self.seed!r}")
        if self.free is not None:
            if isinstance(self.free, str):
                raise ParameterError(f"free must be a sequence of names, got the string {self.free!r}")
            object.__setattr__(self, "free", tuple(self.free) or None)
        object.__setattr__(self, "constants", dict(self.constants or {}))
        if not isinstance(self.sampler, SamplerSettings):
            raise ParameterError(f"sampler must be a SamplerSettings, got {type(self.sampler).__name__}")
        self.sampler.checked()
