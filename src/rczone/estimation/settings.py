"""One settings object for a fit, built once and carried whole to the method.

The command line's options, :func:`rczone.fit`'s keywords and a batch manifest build the same
:class:`FitSettings`, so their defaults cannot drift apart (they did: the API defaulted to least
squares while the command line defaulted to maximum likelihood). It travels unchanged through
:func:`rczone.workflow.checks.fit_and_check`, :func:`rczone.calibration.calibrate` and
:func:`rczone.estimation.fit`; the method's own options ride in it (:attr:`FitSettings.options`),
so a new method's options pass no layer by name.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from rczone import validation
from rczone.errors import ParameterError, did_you_mean
from rczone.estimation.freeset import check_free_and_fixed, fixed_value, resolve_free
from rczone.estimation.methods import DEFAULT_METHOD, MethodOptions, method_of
from rczone.estimation.optimize import OPTIMIZERS
from rczone.simulation.simulate import HOLDS

#: Most local searches of one fit (a typo of a few zeros should not ask for days of searching).
MAX_STARTS = 1000

#: Process-noise placements of an ML or MAP fit (:func:`rczone.estimation.fit.default_free`).
NOISE_PLACEMENTS = ("measured", "all")


@dataclass(frozen=True)
class FitSettings:
    """How to fit: method, free parameters, search, and the checks after the fit.

    Attributes
    ----------
    method : str
        A registered method (:func:`rczone.estimation.methods.method_names`); default ``"ml"``.
    free : tuple of str or None
        Free parameters; None for :func:`rczone.estimation.fit.default_free`. An entry written
        ``"+NAME"`` adds ``NAME`` (a noise level ``sigma_w_Te``, an initial state ``x0_Te``, a
        parameter the model declares fixed) to the default set instead of replacing it.
    optimizer : str
        ``"auto"`` or one of :data:`rczone.estimation.optimize.OPTIMIZERS`; only ``"auto"`` for a
        sampling method, which has no search to choose.
    n_starts : int or None
        Local searches; None for the global search, 1 for one local search; None for a sampling method.
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
    options : MethodOptions
        The method's own options (:attr:`rczone.estimation.methods.Method.options`: a MAP prior's
        spread, a sampler's draws, warm-up and chains); given as an instance or a mapping, kept as
        the method's options class with its defaults filled in. An option the method does not have
        is refused, not dropped. A sampler's seed is :attr:`seed`.
    hold : {"zoh", "foh"}
        Inter-sample behaviour of the inputs: held (zero-order) or linear between samples
        (first-order hold; Franklin, Powell & Workman 1998, sec. 6.3.2). On coarse data the choice
        moves the optimum (pySIP's published fits use FOH).
    bounds : dict of str to (float, float)
        Search bounds overriding the declared ones, in the parameter's SI unit (as the fit table
        prints it), ``lower < upper``.
    fixed : dict of str to float or None
        Parameters held at a value instead of estimated (any R, C or gain, noise level or initial
        state); None holds the model's value (a noise level the model does not carry: its default,
        no process noise).

    References
    ----------
    Franklin, G. F., Powell, J. D. & Workman, M. L. (1998). *Digital Control of Dynamic Systems*,
    3rd ed. Addison-Wesley.
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
    options: MethodOptions | Mapping[str, Any] | None = None
    hold: str = "zoh"
    bounds: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    fixed: Mapping[str, float | None] = field(default_factory=dict)

    def __post_init__(self) -> None:
        method_of(self.method)
        if self.optimizer != "auto" and self.optimizer not in OPTIMIZERS:
            raise ParameterError(
                f"optimizer must be 'auto' or one of {', '.join(OPTIMIZERS)}, got {self.optimizer!r}"
            )
        if self.noise not in NOISE_PLACEMENTS:
            raise ParameterError(f"noise must be one of {', '.join(NOISE_PLACEMENTS)}, got {self.noise!r}")
        if self.n_starts is not None:
            object.__setattr__(
                self,
                "n_starts",
                validation.integer(
                    self.n_starts, "n_starts", low=1, high=MAX_STARTS, besides="None (automatic) or "
                ),
            )
        object.__setattr__(self, "seed", validation.seed(self.seed))
        if self.free is not None:
            if isinstance(self.free, str):
                raise ParameterError(f"free must be a sequence of names, got the string {self.free!r}")
            object.__setattr__(self, "free", tuple(validation.name_list(self.free, "free")) or None)
        object.__setattr__(self, "constants", dict(validation.mapping(self.constants or {}, "constants")))
        object.__setattr__(self, "options", method_of(self.method).make_options(self.options))
        _check_search(self)
        if self.hold not in HOLDS:
            raise ParameterError(f"hold must be one of {', '.join(HOLDS)}, got {self.hold!r}")
        object.__setattr__(self, "bounds", {k: _pair(k, v) for k, v in dict(self.bounds or {}).items()})
        object.__setattr__(self, "fixed", {k: fixed_value(k, v) for k, v in dict(self.fixed or {}).items()})
        check_free_and_fixed(self.free, self.fixed)
        pinned = [n for n in self.bounds if n in self.fixed]
        if pinned:
            raise ParameterError(f"bounds given for {pinned[0]!r}, which is fixed; drop one of the two")

    @classmethod
    def of(
        cls, settings: FitSettings | None = None, /, *, exclude: tuple[str, ...] = (), **overrides: Any
    ) -> FitSettings:
        """``settings`` (default ``FitSettings()``) with ``overrides`` replacing its fields, checked.

        Parameters
        ----------
        settings : FitSettings, optional
        exclude : tuple of str
            Field names the caller takes as its own arguments (refused as overrides).
        **overrides
            Fields of :class:`FitSettings`. Changing ``method`` without ``options`` takes the new
            method's default options (another method's options would be refused).

        Raises
        ------
        ParameterError
            For ``settings`` of another type, or an override that is not a field.
        """
        if settings is not None and not isinstance(settings, cls):
            raise ParameterError(f"settings must be a FitSettings, got {type(settings).__name__}")
        base = settings or cls()
        known = [f.name for f in dataclasses.fields(cls) if f.name not in exclude]
        for name in overrides:
            if name not in known:
                raise ParameterError(
                    f"unexpected keyword {name!r}; {did_you_mean(name, known)} (a FitSettings field)"
                )
        if not overrides:
            return base
        if "method" in overrides and "options" not in overrides and overrides["method"] != base.method:
            overrides = {**overrides, "options": None}
        return dataclasses.replace(base, **overrides)

    def free_for(self, network) -> tuple[str, ...]:
        """The free parameters of a fit of ``network`` (:func:`rczone.estimation.freeset.resolve_free`).

        Parameters
        ----------
        network : RCNetwork
            The model's network.
        """
        return resolve_free(network, self)


def _check_search(s: FitSettings) -> None:
    """Refuse search options a sampling method would ignore: it has no optimizer or starts."""
    if method_of(s.method).search == "sample":
        given = [
            f"{k} {v!r}"
            for k, v in (("optimizer", s.optimizer), ("starts", s.n_starts))
            if v not in ("auto", None)
        ]
        if given:
            raise ParameterError(
                f"method {s.method!r} samples the posterior: {' and '.join(given)} would be ignored (its chains"
                " start around one L-BFGS search); drop them, or choose the search with method 'ml'"
            )


def _pair(name: str, bounds: object) -> tuple[float, float]:
    """``bounds[name]`` as a checked ``(lower, upper)``: finite numbers, ``lower < upper``."""
    try:
        lo, hi = (float(b) for b in bounds)  # type: ignore[union-attr]
    except (TypeError, ValueError):
        raise ParameterError(f"bounds of {name!r} must be a (lower, upper) pair, got {bounds!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise ParameterError(
            f"bounds of {name!r}: lower {lo:g} must be < upper {hi:g}, both finite (they are never swapped)"
        )
    return lo, hi
