"""What an estimation method is: a record of its properties, its own options, and ``run``.

A method is one object (:class:`Method`) that the registry (:mod:`.registry`) holds by name. The
fit pipeline builds one :class:`FitProblem` (the network, the data set, the free parameters with
their bounds, the search budget) and hands it, with the method's options and a seeded random
generator, to :attr:`Method.run`, which returns one :class:`~rczone.estimation.result.FitResult`.
This is lmfit's two-layer shape (``Minimizer.minimize(method=...)`` dispatching to a method
that returns one result type; Newville et al. 2014) with the options owned by the method, as
statsmodels' named option flags are owned by the filter they configure (Seabold & Perktold 2010).

The options of a method are a frozen dataclass derived from :class:`MethodOptions`: their names,
types and defaults are the fields, their checks ``__post_init__``. The same class reads them from
a mapping (the Python API and a batch manifest) and from ``NAME=VALUE`` text (the command line),
so an option is declared once.

References
----------
.. [1] M. Newville, T. Stensitzki, D. B. Allen, A. Ingargiola, "LMFIT: Non-linear least-square
   minimization and curve-fitting for Python", Zenodo, 2014 (one ``minimize(method=...)``).
.. [2] S. Seabold, J. Perktold, "Statsmodels: econometric and statistical modeling with Python",
   Proc. 9th Python in Science Conference, 2010.
"""

from __future__ import annotations

import dataclasses
import math
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from rczone.errors import ParameterError, did_you_mean

if TYPE_CHECKING:
    from rczone.estimation.costs import Objective
    from rczone.estimation.data import Dataset
    from rczone.estimation.parameters import ParameterSpec
    from rczone.estimation.result import FitResult
    from rczone.network import RCNetwork

#: The kernels a method's objective can evaluate: trapezoid squared output error ("ls") or the
#: Kalman filter's negative log-likelihood ("ml").
KERNELS = ("ls", "ml")
#: How a method finds its values: the global search for a minimum, or draws from a posterior.
SEARCHES = ("minimize", "sample")
#: What a fit's RMSE is of.
RMSE_KINDS = ("open-loop", "one-step")


@dataclass(frozen=True, kw_only=True)
class MethodOptions:
    """Base of a method's options: a frozen dataclass whose fields are the options.

    A subclass declares each option as a field with a default and checks the values in
    ``__post_init__`` (raising :class:`~rczone.errors.ParameterError`). :meth:`of` builds the
    options from a mapping, :meth:`parse` from the command line's ``NAME=VALUE`` text.
    """

    @classmethod
    def names(cls) -> tuple[str, ...]:
        """The options' names, in declaration order."""
        return tuple(f.name for f in dataclasses.fields(cls))

    @classmethod
    def of(cls, given: MethodOptions | Mapping[str, Any] | None, method: str) -> MethodOptions:
        """The options of ``method`` from ``given``: an instance, a mapping of names to values, or None.

        Parameters
        ----------
        given : MethodOptions, mapping or None
            None: the defaults.
        method : str
            The method's name, for messages.

        Raises
        ------
        ParameterError
            For an option the method does not have (with the closest name), an instance of
            another method's options, or a value its checks refuse.
        """
        if given is None:
            return cls()
        if isinstance(given, MethodOptions):
            if type(given) is not cls:
                raise ParameterError(
                    f"method {method!r} takes {cls.__name__}, got {type(given).__name__}"
                    f" (the options of another method)"
                )
            return given
        if not isinstance(given, Mapping):
            raise ParameterError(
                f"options of method {method!r} must be a mapping of option names to values, got"
                f" {type(given).__name__}"
            )
        known = cls.names()
        for name in given:
            if name not in known:
                hint = did_you_mean(str(name), known) if known else "it takes no options"
                raise ParameterError(f"method {method!r} has no option {name!r}; {hint}")
        try:
            return cls(**dict(given))
        except TypeError as exc:  # a dataclass's own complaint about an argument
            raise ParameterError(f"options of method {method!r}: {exc}") from None

    @classmethod
    def parse(cls, items: typing.Iterable[str], method: str) -> MethodOptions:
        """The options from ``NAME=VALUE`` texts (``--option``), each value read by the field's type.

        ``int`` and ``float`` fields take a number, ``bool`` fields ``true``/``false``, tuple fields
        a comma-separated list, ``str`` fields the text.
        """
        hints = typing.get_type_hints(cls)
        values: dict[str, Any] = {}
        for item in items:
            name, sep, text = str(item).partition("=")
            name = name.strip()
            if not sep or not name:
                raise ParameterError(f"option {item!r} must be NAME=VALUE (e.g. draws=500)")
            if name not in hints:
                cls.of({name: None}, method)  # the message with the closest name
            values[name] = _read(text.strip(), hints[name], name)
        return cls.of(values, method)

    def to_dict(self) -> dict[str, Any]:
        """The options by name (JSON-ready: tuples become lists)."""
        return {k: list(v) if isinstance(v, tuple) else v for k, v in dataclasses.asdict(self).items()}


def _read(text: str, kind: Any, name: str) -> Any:
    """``text`` as a value of type ``kind`` (int, float, bool, str or a tuple of int/float)."""
    origin = typing.get_origin(kind)
    try:
        if origin is tuple:
            item = typing.get_args(kind)[0]
            return tuple(_read(t.strip(), item, name) for t in text.split(",") if t.strip())
        if kind is bool:
            low = text.lower()
            if low not in ("true", "false", "1", "0", "yes", "no"):
                raise ValueError
            return low in ("true", "1", "yes")
        if kind is int:
            if not text.lstrip("+-").isascii() or not text.lstrip("+-").isdigit():
                raise ValueError
            return int(text)
        if kind is float:
            v = float(text)
            if not math.isfinite(v):
                raise ValueError
            return v
    except ValueError:
        label = getattr(kind, "__name__", str(kind))
        raise ParameterError(f"option {name}: {text!r} is not a valid {label}") from None
    return text


@dataclass(frozen=True, kw_only=True)
class NoOptions(MethodOptions):
    """A method without options of its own."""


def positive_int(options: MethodOptions, name: str, low: int, high: int) -> None:
    """Refuse ``options.name`` unless it is an integer in ``[low, high]`` (a bool is not an integer)."""
    v = getattr(options, name)
    if isinstance(v, bool) or not isinstance(v, int) or not low <= v <= high:
        raise ParameterError(f"option {name} must be an integer from {low} to {high:,}, got {v!r}")


def positive_float(options: MethodOptions, name: str) -> None:
    """Refuse ``options.name`` unless it is a finite number > 0."""
    v = getattr(options, name)
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not (math.isfinite(v) and v > 0):
        raise ParameterError(f"option {name} must be a finite number > 0, got {v!r}")


@dataclass(frozen=True, eq=False)
class FitProblem:
    """What a method is asked to solve: one network, one data set, the free parameters, the budget.

    Built once by :func:`rczone.estimation.fit.fit`; a method reads it and never changes it.

    Attributes
    ----------
    network : RCNetwork
        The model structure; its declared values are the construction values.
    data : Dataset
        The data set, checked against the network.
    spec : ParameterSpec
        Free parameters with bounds, transforms, start values and the values of the others.
    method : str
        The registered name of the method that runs (recorded in the result).
    hold : {"zoh", "foh"}
        Inter-sample behaviour of the inputs.
    optimizer : str
        The local method requested (``"auto"`` or one of
        :data:`rczone.estimation.optimize.OPTIMIZERS`); a sampling method ignores it.
    n_starts : int or None
        Local searches: None for the global search, ``k`` for exactly ``k``.
    max_evals : int or None
        Evaluation budget per local search.
    uncertainty : bool
        Whether to compute standard errors and correlations.
    progress : object, optional
        Told how far the search or the sampler is (``progress.advance(done, total)``); None: nothing.
    """

    network: RCNetwork
    data: Dataset
    spec: ParameterSpec
    method: str
    hold: str = "zoh"
    optimizer: str = "auto"
    n_starts: int | None = None
    max_evals: int | None = None
    uncertainty: bool = True
    progress: Any = None

    def objective(self, *, kernel_method: str | None = None, prior_spread: float | None = None,
                  likelihood_weight: float = 1.0) -> Objective:  # fmt: skip
        """The objective of this problem evaluated by ``kernel_method``'s kernel (default: the method's own).

        Parameters
        ----------
        kernel_method : str, optional
            The registered method whose objective to build (a sampler builds ``"ml"``'s).
        prior_spread : float, optional
            Spread (log units) of a MAP prior; default that of :mod:`rczone.estimation.priors`.
        likelihood_weight : float
            ``w`` of a tempered likelihood (:class:`~rczone.estimation.costs.Objective`).
        """
        from rczone.estimation.costs import PRIOR_SPREAD, Objective

        spread = PRIOR_SPREAD if prior_spread is None else prior_spread
        return Objective(
            self.network,
            self.data,
            self.spec,
            kernel_method or self.method,
            self.hold,
            spread,
            likelihood_weight,
        )

    def output_error(self, theta: np.ndarray) -> np.ndarray:
        """``y - y_hat`` of the open-loop simulation at the free values ``theta``, K, shape (N, n_outputs).

        The unmeasured states start at their ``x0_`` values where they are free or fixed, else in
        equilibrium with the first inputs (:func:`rczone.estimation.costs.auto_initial_state`).
        """
        from rczone.estimation.costs import simulate_output

        values = self.spec.values(np.asarray(theta, dtype=float))
        return self.data.y - simulate_output(self.network, values, self.data, self.hold)[1]

    @property
    def sample_time_s(self) -> float:
        """The data's median sample interval, s."""
        return float(np.median(np.diff(self.data.t)))


#: ``run(problem, options, rng) -> FitResult``.
Runner = Callable[[FitProblem, MethodOptions, np.random.Generator], "FitResult"]


@dataclass(frozen=True, kw_only=True)
class Method:
    """An estimation method: what the rest of rczone needs to know of it, its options and ``run``.

    Attributes
    ----------
    name : str
        The method's name on the command line and in the API (``--method``, ``method=``).
    title : str
        What it is, in a few words (help texts).
    kernel : {"ls", "ml"}
        The kernel cost its objective evaluates: trapezoid squared output error, or the Kalman
        filter's negative log-likelihood.
    stochastic : bool
        Whether the model has a noise model (measurement and process noise are estimated, the
        objective is a likelihood, the residuals are innovations).
    prior : bool
        Whether the objective adds a prior to a tempered likelihood (MAP).
    objective : str
        What the objective value means, with its unit.
    rmse_kind : {"open-loop", "one-step"}
        The error the fit's RMSE is of.
    abs_tol, rel_tol : float
        Objective differences below ``abs_tol + rel_tol |objective|`` are the same optimum.
    search : {"minimize", "sample"}
        The global search for a minimum, or draws from the posterior; a sampling method takes no
        optimizer or starts.
    options : type
        Its options, a subclass of :class:`MethodOptions` (:class:`NoOptions` for none).
    run : callable
        ``run(problem, options, rng) -> FitResult``.
    """

    name: str
    title: str
    kernel: str
    stochastic: bool
    objective: str
    rmse_kind: str
    run: Runner = dataclasses.field(repr=False, compare=False)
    prior: bool = False
    abs_tol: float = 0.01
    rel_tol: float = 1e-9
    search: str = "minimize"
    options: type[MethodOptions] = NoOptions

    def __post_init__(self) -> None:
        if not (isinstance(self.name, str) and self.name.isidentifier() and self.name.isascii()):
            raise ParameterError(f"a method's name must be an ASCII identifier, got {self.name!r}")
        for field, allowed in (("kernel", KERNELS), ("search", SEARCHES), ("rmse_kind", RMSE_KINDS)):
            if getattr(self, field) not in allowed:
                raise ParameterError(
                    f"method {self.name!r}: {field} must be one of {', '.join(allowed)}, got"
                    f" {getattr(self, field)!r}"
                )
        if not (isinstance(self.options, type) and issubclass(self.options, MethodOptions)):
            raise ParameterError(f"method {self.name!r}: options must be a MethodOptions subclass")
        if not callable(self.run):
            raise ParameterError(f"method {self.name!r}: run must be callable")

    def make_options(self, given: MethodOptions | Mapping[str, Any] | None = None) -> MethodOptions:
        """This method's options from ``given`` (:meth:`MethodOptions.of`)."""
        return self.options.of(given, self.name)
