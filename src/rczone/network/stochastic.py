"""The stochastic parameters of a network: noise levels and initial states, by kind.

A Kalman-filter likelihood of a network's state space

.. math::

    dx = (A x + B u)\\,dt + \\Sigma_w\\,dW, \\qquad y_k = C x_k + D u_k + v_k, \\qquad
    x_0 \\sim N(\\bar x_0, \\Sigma_{x_0})

(Kristensen, Madsen & Jørgensen 2004, eq. 1-3; Bacher & Madsen 2011, sec. 3) needs four kinds of
parameters beside the network's own resistances and capacitances:

========================  ======================  ==========  =================================
kind                      name                    unit        meaning
========================  ======================  ==========  =================================
``measurement_noise``     ``sigma_v``             K           standard deviation of ``v`` (one output)
``measurement_noise``     ``sigma_v_<output>``    K           the same per output of a multi-output network
``process_noise``         ``sigma_w_<state>``     K/sqrt(s)   diffusion of the state ``<state>``
``initial_state``         ``x0_<state>``          degC        mean of the initial state
``initial_spread``        ``sigma_x0_<state>``    K           standard deviation of the initial state
========================  ======================  ==========  =================================

This module is the only place that spells those names: every other module builds them with
:func:`measurement_noise_names`, :func:`process_noise_name` and their siblings, and reads them with
:func:`parse_name` (``tests/unit/network/test_stochastic_names.py`` fails on a prefix spelled
elsewhere). A network parameter may not start with a prefix reserved here
(:data:`RESERVED_PREFIXES`), so a name is never both.

References
----------
Kristensen, N. R., Madsen, H. & Jørgensen, S. B. (2004). Parameter estimation in stochastic grey-box
models. *Automatica* 40(2), 225-237.
Bacher, P. & Madsen, H. (2011). Identifying suitable models for the heat dynamics of buildings.
*Energy and Buildings* 43(7), 1511-1522.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from rczone.errors import ParameterError, did_you_mean

#: The four kinds of stochastic parameter.
MEASUREMENT_NOISE = "measurement_noise"
PROCESS_NOISE = "process_noise"
INITIAL_STATE = "initial_state"
INITIAL_SPREAD = "initial_spread"


@dataclass(frozen=True)
class StochasticKind:
    """How one kind of stochastic parameter is named and estimated.

    Attributes
    ----------
    kind : str
        One of :data:`MEASUREMENT_NOISE`, :data:`PROCESS_NOISE`, :data:`INITIAL_STATE`,
        :data:`INITIAL_SPREAD`.
    prefix : str
        Start of the name; the target (state or output) follows it.
    target : {"output", "state"}
        What the parameter belongs to.
    unit : str
        SI unit of its value.
    role : {"noise", "state"}
        The estimation's parameter kind: ``"noise"`` is a standard deviation (> 0, estimated in log
        space), ``"state"`` a temperature (estimated as is).
    default : float or None
        Value when neither free nor given (None: derived from the data, see
        :func:`rczone.estimation.parameters.auto_initial_state`).
    """

    kind: str
    prefix: str
    target: str
    unit: str
    role: str
    default: float | None


_MEASUREMENT = StochasticKind(MEASUREMENT_NOISE, "sigma_v", "output", "K", "noise", 0.1)
_PROCESS = StochasticKind(PROCESS_NOISE, "sigma_w_", "state", "K/sqrt(s)", "noise", 1e-3)
_INITIAL = StochasticKind(INITIAL_STATE, "x0_", "state", "degC", "state", None)
_SPREAD = StochasticKind(INITIAL_SPREAD, "sigma_x0_", "state", "K", "noise", 1.0)

#: kind -> its description, in the order of :func:`stochastic_parameter_names`.
KINDS = {k.kind: k for k in (_MEASUREMENT, _PROCESS, _INITIAL, _SPREAD)}

#: Starts of names reserved for stochastic parameters (a network parameter may not use them).
RESERVED_PREFIXES = ("sigma_", "x0_")

#: Value of a process noise that is neither free nor given: no process noise on a state whose noise
#: is not estimated. (A fixed nonzero intensity on an unmeasured wall or slab node, e.g. the start
#: value 1e-3 K/sqrt(s), i.e. a random walk of 0.06 K per hour, is a strong claim the data never
#: checked; on a synthetic zone with exact structure it biased the ML estimates of R and C by
#: 20-27 % where zero gives the truth within the standard errors.)
FIXED_PROCESS_NOISE = 0.0


@dataclass(frozen=True)
class StochasticName:
    """A stochastic parameter's name read back: its kind and the state or output it belongs to.

    Attributes
    ----------
    kind : str
        A key of :data:`KINDS`.
    target : str or None
        The state (or output) named after the prefix; None for the single output's ``sigma_v``.
    name : str
        The full name.
    """

    kind: str
    target: str | None
    name: str

    @property
    def spec(self) -> StochasticKind:
        """The kind's description (prefix, unit, role, default)."""
        return KINDS[self.kind]


def parameter_name(kind: str, target: str | None) -> str:
    """The name of the ``kind`` parameter of ``target`` (a state, or an output; None: the only output).

    Raises
    ------
    ParameterError
        For an unknown kind, or a missing target of a per-state kind.
    """
    k = KINDS.get(kind)
    if k is None:
        raise ParameterError(
            f"unknown stochastic parameter kind {kind!r}; " + did_you_mean(kind, tuple(KINDS))
        )
    if kind == MEASUREMENT_NOISE:
        return k.prefix if target is None else f"{k.prefix}_{target}"
    if not target:
        raise ParameterError(f"a {kind} parameter belongs to a state; name it (got {target!r})")
    return k.prefix + target


def measurement_noise_names(outputs: Sequence[str]) -> tuple[str, ...]:
    """``("sigma_v",)`` for one output, else ``sigma_v_<output>`` per output (``R`` is their squares)."""
    if len(outputs) == 1:
        return (parameter_name(MEASUREMENT_NOISE, None),)
    return tuple(parameter_name(MEASUREMENT_NOISE, o) for o in outputs)


def process_noise_name(state: str) -> str:
    """``sigma_w_<state>``."""
    return parameter_name(PROCESS_NOISE, state)


def initial_state_name(state: str) -> str:
    """``x0_<state>``."""
    return parameter_name(INITIAL_STATE, state)


def initial_spread_name(state: str) -> str:
    """``sigma_x0_<state>``."""
    return parameter_name(INITIAL_SPREAD, state)


def process_noise_names(states: Iterable[str]) -> tuple[str, ...]:
    """``sigma_w_<state>`` per state."""
    return tuple(process_noise_name(s) for s in states)


def initial_state_names(states: Iterable[str]) -> tuple[str, ...]:
    """``x0_<state>`` per state."""
    return tuple(initial_state_name(s) for s in states)


def initial_spread_names(states: Iterable[str]) -> tuple[str, ...]:
    """``sigma_x0_<state>`` per state."""
    return tuple(initial_spread_name(s) for s in states)


def stochastic_parameter_names(outputs: Sequence[str], states: Sequence[str]) -> tuple[str, ...]:
    """Every stochastic parameter of a network: measurement, process noise, initial states, spreads."""
    return (
        *measurement_noise_names(outputs),
        *process_noise_names(states),
        *initial_state_names(states),
        *initial_spread_names(states),
    )


def parse_name(name: str) -> StochasticName | None:
    """The kind and target of a stochastic parameter's name; None for any other name.

    ``sigma_v`` has no target (the single output); a name that is only a prefix
    (``sigma_w_``, ``x0_``) or starts with ``sigma_v`` without the separator (``sigma_vx``) is not
    a stochastic name.
    """
    if not isinstance(name, str):
        return None
    if name == _MEASUREMENT.prefix:
        return StochasticName(MEASUREMENT_NOISE, None, name)
    for k, prefix in (
        (_MEASUREMENT, _MEASUREMENT.prefix + "_"),
        (_PROCESS, _PROCESS.prefix),
        (_SPREAD, _SPREAD.prefix),
        (_INITIAL, _INITIAL.prefix),
    ):
        if name.startswith(prefix) and len(name) > len(prefix):
            return StochasticName(k.kind, name[len(prefix) :], name)
    return None


def kind_of(name: str) -> str | None:
    """The kind of a stochastic parameter's name (a key of :data:`KINDS`); None for any other name."""
    p = parse_name(name)
    return None if p is None else p.kind


def target_of(name: str) -> str | None:
    """The state or output a stochastic name belongs to (None for ``sigma_v`` and other names)."""
    p = parse_name(name)
    return None if p is None else p.target


def is_noise_name(name: str) -> bool:
    """True for a noise standard deviation: measurement, process noise or initial spread."""
    p = parse_name(name)
    return p is not None and p.spec.role == "noise"


def is_reserved(name: object, *, noise_only: bool = False) -> bool:
    """True when ``name`` starts with a prefix reserved for stochastic parameters.

    Looser than :func:`parse_name` (``sigma_foo`` is reserved but names no parameter): it is what a
    network parameter may not be called, and what a model file's ``noise`` table may hold.

    Parameters
    ----------
    name : object
        A name (converted with ``str``).
    noise_only : bool
        Only the prefix of noise standard deviations (``sigma_``), not that of initial states.
    """
    return str(name).startswith(RESERVED_PREFIXES[:1] if noise_only else RESERVED_PREFIXES)


def default_value(name: str) -> float | None:
    """The declared default of a stochastic parameter (None for ``x0_*`` and for other names)."""
    p = parse_name(name)
    return None if p is None else p.spec.default


def unit_of(name: str) -> str | None:
    """The unit of a stochastic parameter (None for any other name)."""
    p = parse_name(name)
    return None if p is None else p.spec.unit
