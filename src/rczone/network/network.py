"""Declarative RC networks: nodes, resistors, heat inputs and supply air.

An :class:`RCNetwork` is frozen data describing the topology of a thermal network and
the names of its parameters. :meth:`RCNetwork.state_space` turns it, for given parameter
values, into the continuous-time bilinear state space

.. math::

    \\dot x = (A + \\textstyle\\sum_k m_k N_k)\\,x + (B + \\textstyle\\sum_k m_k M_k)\\,u,
    \\qquad y = C x + D u

where the flows :math:`m_k` (kg/s) are the mass-flow inputs of the supply-air elements.

Conventions
-----------
* Temperatures in K or degC (the equations are affine-invariant), heat flows in W,
  resistances in K/W, capacities in J/K, mass flows in kg/s, time in s.
* A node with ``capacity=None`` is massless: its energy balance is algebraic and it is
  eliminated exactly (Kron reduction of the conductance matrix).
* A supply-air element adds ``m * cp * (T_supply - T_node)`` W to a capacitive node.

References
----------
.. [1] Y. Lin, T. Middelkoop, P. Barooah, "Issues in identification of control-oriented
   thermal models of zones in multi-zone buildings", IEEE CDC 2012, eqs. (1)-(4).
.. [2] F. Doerfler, F. Bullo, "Kron reduction of graphs with applications to electrical
   networks", IEEE Trans. Circuits Syst. I, 60(1), 2013.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import NamedTuple

import numpy as np

from rczone.errors import NetworkError, ParameterError, did_you_mean
from rczone.network.disturbance import ROLE_KINDS, LatentForce, latent_sde
from rczone.network.parameters import (
    ESTIMATED_KINDS,
    Parameter,
    check_declarations,
    evaluate_ties,
    resolve,
)
from rczone.network.prior import Prior
from rczone.network.statespace import BilinearStateSpace, StateSpaceDerivative

#: Specific heat of air at constant pressure, J/(kg K), used when none is given.
CP_AIR = 1005.0

Value = str | float

#: SI units a heat input's signal may have (the split's gains make W of it).
HEAT_INPUT_UNITS = ("W", "W/m2")


def _check_positive(values: np.ndarray, names: Sequence[Value], what: str) -> None:
    """Element values must be positive, whatever kind their parameter was declared with."""
    real = values.real if np.iscomplexobj(values) else values
    bad = np.flatnonzero(~(real > 0))
    if bad.size:
        i = int(bad[0])
        raise ParameterError(f"{what} {names[i]!r} must be > 0, got {real[i]:g}")


@dataclass(frozen=True)
class Node:
    """A temperature node of the network.

    Parameters
    ----------
    name : str
        Node (state) name, e.g. ``"Ti"``.
    capacity : str or float or None
        Parameter name or value of the heat capacity (J/K); ``None`` for a massless node.
    description : str
        Free text for reports.
    """

    name: str
    capacity: Value | None = None
    description: str = ""


@dataclass(frozen=True)
class Resistor:
    """A thermal resistance (K/W) between two nodes or a node and a boundary.

    Parameters
    ----------
    a, b : str
        The nodes (or boundary) it connects.
    resistance : str or float
        A parameter name, or a value in K/W.
    """

    a: str
    b: str
    resistance: Value


@dataclass(frozen=True)
class HeatInput:
    """A heat-flow input (W) delivered to one or several nodes.

    Parameters
    ----------
    name : str
        Input name, e.g. ``"Q"``.
    split : mapping of node name to gain
        Fraction (or any gain; a parameter name or a number) of the input delivered to
        each node. ``{"Ti": 1.0}`` puts it all on ``Ti``.
    unit : {"W", "W/m2"}
        SI unit of the input signal: a heat flow, or an irradiance that gains in m2 (an
        effective aperture such as ``Aw``) turn into a heat flow.
    """

    name: str
    split: tuple[tuple[str, Value], ...]
    unit: str = "W"

    def __init__(self, name: str, split: Mapping[str, Value] | str, unit: str = "W") -> None:
        if isinstance(split, str):
            split = {split: 1.0}
        if not isinstance(split, Mapping):
            raise NetworkError(f"heat input {name!r}: split must map node names to gains, got {split!r}")
        if unit not in HEAT_INPUT_UNITS:
            raise NetworkError(
                f"heat input {name!r}: unit {unit!r} is not one of {', '.join(HEAT_INPUT_UNITS)}"
                " (SI units of the input signal; the gains turn it into W)"
            )
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "split", tuple(split.items()))
        object.__setattr__(self, "unit", unit)


@dataclass(frozen=True)
class SupplyAir:
    """Supply air entering ``node``: heat ``flow * cp * (temperature - T_node)`` W.

    Parameters
    ----------
    node : str
        Capacitive node the air is mixed into (the room air).
    flow : str
        Name of the mass-flow input (kg/s).
    temperature : str
        Name of the supply temperature input; may be a boundary temperature (ventilation
        with outdoor air) or an input of its own.
    cp : float or str
        Specific heat of air, J/(kg K).
    """

    node: str
    flow: str = "m"
    temperature: str = "Ts"
    cp: Value = CP_AIR


def _elements(items: object, kind: type | tuple[type, ...], what: str) -> tuple:
    """``items`` as a tuple of ``kind`` objects, or one line naming the argument (not a TypeError)."""
    if isinstance(items, (str, bytes, Mapping)) or not isinstance(items, Iterable):
        raise NetworkError(f"{what} must be a sequence, got {type(items).__name__}")
    out = tuple(items)
    wrong = next((x for x in out if not isinstance(x, kind)), None)
    if wrong is not None:
        expected = kind.__name__ if isinstance(kind, type) else kind[0].__name__
        raise NetworkError(f"{what} must hold {expected} objects, got {type(wrong).__name__}")
    return out


def _as_params(parameters: Iterable[Parameter] | Mapping[str, Parameter]) -> dict[str, Parameter]:
    items = (
        parameters.values()
        if isinstance(parameters, Mapping)
        else _elements(parameters, Parameter, "parameters")
    )
    out: dict[str, Parameter] = {}
    for p in items:
        if not isinstance(p, Parameter):
            raise NetworkError(f"parameters must be Parameter objects, got {type(p).__name__}")
        if p.name in out:
            raise NetworkError(f"parameter {p.name!r} is declared twice")
        out[p.name] = p
    return out


@dataclass(frozen=True, eq=False)
class ConductanceForm:
    """Constant arrays of a network without massless nodes (see :attr:`RCNetwork.conductance_form`)."""

    L: np.ndarray
    P: np.ndarray
    E: np.ndarray
    Gb0: np.ndarray
    Nf: np.ndarray
    Mf: np.ndarray
    resistances: tuple
    capacities: tuple
    output_state: tuple[int, ...]
    gains: tuple[tuple[int, int, str], ...] = ()
    """Heat-input gains that are parameters: ``(state, input, parameter)``, added to ``Gb0``."""


class BilinearMatrices(NamedTuple):
    """What :meth:`RCNetwork._assemble` builds: the bilinear matrices and the per-state constants."""

    A: np.ndarray
    """(n, n)"""
    N: np.ndarray
    """(n_flows, n, n)"""
    B: np.ndarray
    """(n, p)"""
    M: np.ndarray
    """(n_flows, n, p)"""
    C: np.ndarray
    """(ny, n)"""
    D: np.ndarray
    """(ny, p)"""
    capacities: np.ndarray
    """Heat capacity per state, J/K (NaN for a latent state of a disturbance)."""
    diffusion: np.ndarray
    """Per-state diffusion intensity the network itself declares (the disturbances' SDEs), 1/s."""


RESERVED_NAMES = frozenset({"time"})
"""Names no node or signal may take: ``time`` is the data's time-stamp column."""
MAX_STATES = 200
"""Most capacitive nodes (states) of a network: a zone's models have 1 to 15, the virtual
building's emulator 152. Simulation, filtering and fitting grow with the cube of the states; a
thousand-node chain would run for hours."""


@dataclass(frozen=True)
class RCNetwork:
    """A frozen RC-network description from which state spaces are built.

    Parameters
    ----------
    name : str
        Model name for reports.
    nodes : sequence of Node
        Temperature nodes; capacitive ones become states in declaration order.
    boundaries : sequence of str
        Names of prescribed (input) temperatures, e.g. ``("To", "Tsd")``.
    resistors : sequence of Resistor
    parameters : sequence of Parameter
        Every parameter that elements refer to by name.
    heat_inputs : sequence of HeatInput
    supply_air : sequence of SupplyAir
    outputs : sequence of str
        Nodes that are measured; default: the first node.
    description : str
        What the network models, in words (for listings and reports).
    disturbances : sequence of LatentForce
        Unmeasured heat inputs with a Gaussian-process prior (:mod:`rczone.network.disturbance`);
        their latent states follow the nodes' states.

    Examples
    --------
    The paper's 2nd-order model (eq. 4) without the supply air:

    >>> from rczone.network import RCNetwork, Node, Resistor, HeatInput, Parameter
    >>> net = RCNetwork(
    ...     "2R1C", nodes=[Node("Ti", "Cr"), Node("Tw", "Cw")], boundaries=["To", "Tsd"],
    ...     resistors=[Resistor("Ti", "To", "Rwin"), Resistor("Ti", "Tw", "R1"),
    ...                Resistor("Tw", "Tsd", "R2")],
    ...     heat_inputs=[HeatInput("Q", {"Ti": 1.0})],
    ...     parameters=[Parameter("Cr", "capacitance", 1e5), Parameter("Cw", "capacitance", 1e7),
    ...                 Parameter("Rwin", "resistance", 0.1), Parameter("R1", "resistance", 0.01),
    ...                 Parameter("R2", "resistance", 0.01)])
    >>> net.state_space().state_names
    ('Ti', 'Tw')
    """

    name: str
    nodes: tuple[Node, ...]
    boundaries: tuple[str, ...]
    resistors: tuple[Resistor, ...]
    parameters: dict[str, Parameter] = field(default_factory=dict)
    heat_inputs: tuple[HeatInput, ...] = ()
    supply_air: tuple[SupplyAir, ...] = ()
    outputs: tuple[str, ...] = ()
    description: str = ""
    disturbances: tuple[LatentForce, ...] = ()

    def __init__(
        self,
        name: str,
        nodes: Iterable[Node],
        boundaries: Iterable[str],
        resistors: Iterable[Resistor],
        parameters: Iterable[Parameter] | Mapping[str, Parameter] = (),
        heat_inputs: Iterable[HeatInput] = (),
        supply_air: Iterable[SupplyAir] = (),
        outputs: Iterable[str] | None = None,
        description: str = "",
        *,
        disturbances: Iterable[LatentForce] = (),
    ) -> None:
        nodes = _elements(nodes, Node, "nodes")
        set_ = object.__setattr__
        set_(self, "name", name)
        set_(self, "nodes", nodes)
        set_(self, "boundaries", _elements(boundaries, str, "boundaries"))
        set_(self, "resistors", _elements(resistors, Resistor, "resistors"))
        set_(self, "parameters", _as_params(parameters))
        set_(self, "heat_inputs", _elements(heat_inputs, HeatInput, "heat_inputs"))
        set_(self, "supply_air", _elements(supply_air, SupplyAir, "supply_air"))
        outputs = _elements(outputs, str, "outputs") if outputs is not None else None
        set_(self, "outputs", outputs if outputs is not None else (nodes[0].name,) if nodes else ())
        set_(self, "description", description)
        set_(self, "disturbances", _elements(disturbances, LatentForce, "disturbances"))
        self._validate()

    def __hash__(self) -> int:  # parameters is a dict; identity hash suffices for caching
        return id(self)

    # ------------------------------------------------------------------ names
    @cached_property
    def state_names(self) -> tuple[str, ...]:
        """Names of the states, in order: the capacitive nodes, then the disturbances' latent states."""
        return self.node_state_names + self.latent_state_names

    @cached_property
    def node_state_names(self) -> tuple[str, ...]:
        """Names of the capacitive nodes (the thermal states), in order."""
        return tuple(n.name for n in self.nodes if n.capacity is not None)

    @cached_property
    def latent_state_names(self) -> tuple[str, ...]:
        """Names of the disturbances' latent states (:mod:`rczone.network.disturbance`), in order."""
        return tuple(s for d in self.disturbances for s in d.state_names)

    @cached_property
    def massless_names(self) -> tuple[str, ...]:
        """Names of the massless (eliminated) nodes."""
        return tuple(n.name for n in self.nodes if n.capacity is None)

    @cached_property
    def flow_names(self) -> tuple[str, ...]:
        """Names of the mass-flow inputs, in order of first use."""
        return tuple(dict.fromkeys(s.flow for s in self.supply_air))

    @cached_property
    def input_names(self) -> tuple[str, ...]:
        """Names of the (non-flow) inputs: boundary temperatures, supply temperatures, heat."""
        temps = list(self.boundaries)
        temps += [s.temperature for s in self.supply_air if s.temperature not in temps]
        return tuple(dict.fromkeys(temps)) + tuple(h.name for h in self.heat_inputs)

    @cached_property
    def _tie_order(self) -> tuple[str, ...]:
        return check_declarations(self.parameters)

    @property
    def free_parameter_names(self) -> tuple[str, ...]:
        """Base (untied) parameter names."""
        return tuple(n for n, p in self.parameters.items() if not p.is_tied)

    @property
    def priors(self) -> dict[str, Prior]:
        """The declared priors (:mod:`rczone.network.prior`), by parameter name."""
        return {n: p.prior for n, p in self.parameters.items() if p.prior is not None}

    @property
    def default_free(self) -> tuple[str, ...]:
        """Parameters a fit estimates unless told otherwise.

        Every base resistance, capacitance and gain not declared ``fixed`` (the declaration
        is the model's, so a model file or a built-in model says what is usually estimated;
        the paper's reduced model, for example, fixes ``Cw`` and ``Rwin``).
        """
        return tuple(
            n
            for n, p in self.parameters.items()
            if not p.is_tied and not p.fixed and p.kind in ESTIMATED_KINDS
        )

    # -------------------------------------------------------------- validation
    def _validate(self) -> None:
        node_names = [n.name for n in self.nodes]
        if not node_names:
            raise NetworkError(f"network {self.name!r} has no nodes")
        signals = [
            *node_names,
            *self.boundaries,
            *(h.name for h in self.heat_inputs),
            *(x for s in self.supply_air for x in (s.flow, s.temperature, s.node)),
            *self.outputs,
        ]
        for nm in signals:
            if not isinstance(nm, str) or not nm.strip() or any(ord(ch) < 32 for ch in nm):
                raise NetworkError(
                    f"network {self.name!r}: {nm!r} is not a usable node or signal name"
                    " (a non-empty string without control characters)"
                )
        for nm in signals:
            if nm in RESERVED_NAMES:
                raise NetworkError(
                    f"network {self.name!r}: {nm!r} is reserved for the data's time stamps; rename the node or"
                    " signal (rczone.network.network.RESERVED_NAMES)"
                )
        seen: set[str] = set()
        for nm in (*node_names, *self.boundaries):
            if nm in seen:
                raise NetworkError(f"network {self.name!r}: name {nm!r} is declared twice")
            seen.add(nm)
        if len(set(self.outputs)) < len(self.outputs):
            dup = next(o for o in self.outputs if self.outputs.count(o) > 1)
            raise NetworkError(f"network {self.name!r}: output {dup!r} is listed twice")
        for sa in self.supply_air:
            if sa.temperature == sa.flow:
                raise NetworkError(
                    f"network {self.name!r}: supply air at {sa.node!r} uses {sa.flow!r} as both its flow and"
                    " its temperature; give them different names"
                )
        if not self.node_state_names:
            raise NetworkError(f"network {self.name!r} has no capacitive node, so no states")
        if len(self.node_state_names) > MAX_STATES:
            raise NetworkError(
                f"network {self.name!r} has {len(self.node_state_names)} capacitive nodes (states), more than the"
                f" limit of {MAX_STATES} (rczone.network.network.MAX_STATES); lump thin layers into fewer nodes"
            )
        known = set(node_names) | set(self.boundaries)
        params = self.parameters

        def check_value(v: Value | None, where: str, kind: str) -> None:
            if v is None:
                return
            if isinstance(v, str):
                if v not in params:
                    raise NetworkError(
                        f"{where} refers to undeclared parameter {v!r}; " + did_you_mean(v, params)
                    )
                if kind in ("resistance", "capacitance") and params[v].kind not in (kind, "other"):
                    raise NetworkError(f"{where} uses {v!r}, declared as a {params[v].kind}, not a {kind}")
            else:
                try:
                    if isinstance(v, bool):
                        raise TypeError
                    val = float(v)
                except (TypeError, ValueError, OverflowError):
                    raise NetworkError(f"{where}: {v!r} is neither a number nor a parameter name") from None
                if not math.isfinite(val):
                    raise ParameterError(f"{where}: {val!r} is not finite")
                if kind in ("resistance", "capacitance", "positive") and not val > 0:
                    raise ParameterError(f"{where}: a {kind} must be > 0, got {val:g}")

        def check_node(n: str, where: str, allowed: Iterable[str]) -> None:
            if n not in allowed:
                raise NetworkError(f"{where} refers to undeclared node {n!r}; " + did_you_mean(n, known))

        for nd in self.nodes:
            check_value(nd.capacity, f"node {nd.name!r} capacity", "capacitance")
        for i, r in enumerate(self.resistors):
            where = f"resistor #{i} ({r.a}-{r.b})"
            check_node(r.a, where, known)
            check_node(r.b, where, known)
            if r.a == r.b:
                raise NetworkError(f"{where} connects node {r.a!r} to itself")
            if r.a in self.boundaries and r.b in self.boundaries:
                raise NetworkError(f"{where} connects two boundary temperatures; it carries no state")
            check_value(r.resistance, where, "resistance")
        input_seen = set(self.boundaries)
        for h in self.heat_inputs:
            if h.name in input_seen or h.name in node_names:
                raise NetworkError(f"heat input {h.name!r} reuses a node or input name")
            input_seen.add(h.name)
            if not h.split:
                raise NetworkError(f"heat input {h.name!r} is delivered to no node")
            for nd, g in h.split:
                check_node(nd, f"heat input {h.name!r}", node_names)
                check_value(g, f"heat input {h.name!r} gain", "")
        for s in self.supply_air:
            check_node(s.node, f"supply air ({s.flow})", node_names)
            if s.node in self.massless_names:
                raise NetworkError(
                    f"supply air {s.flow!r} enters massless node {s.node!r}; the bilinear form needs"
                    " a capacitive node there (give the air node its capacity)"
                )
            if s.flow in known or s.flow in {h.name for h in self.heat_inputs}:
                raise NetworkError(f"flow name {s.flow!r} clashes with a node or input name")
            if s.temperature in node_names:
                raise NetworkError(f"supply temperature {s.temperature!r} is a node, not an input")
            check_value(s.cp, f"supply air {s.flow!r} cp", "positive")
        for o in self.outputs:
            check_node(o, "output", node_names)
        self._check_disturbances(set(seen) | input_seen | set(self.flow_names), check_node, check_value)
        self._check_floating()
        _ = self._tie_order

    def _check_disturbances(self, taken: set[str], check_node, check_value) -> None:
        """Disturbances: unique names, known nodes, hyper-parameters of the right kind and sign."""
        node_names = [n.name for n in self.nodes]
        for d in self.disturbances:
            if not isinstance(d, LatentForce):
                raise NetworkError(f"disturbances must be LatentForce objects, got {type(d).__name__}")
            where = f"disturbance {d.name!r}"
            for s in d.state_names:
                if s in taken or s in RESERVED_NAMES:
                    raise NetworkError(
                        f"{where}: its state {s!r} reuses a node, input or state name; rename it"
                    )
                taken.add(s)
            for nd, g in d.gains:
                check_node(nd, where, node_names)
                check_value(g, f"{where} gain at {nd!r}", "")
            for role, v in d.hyperparameters:
                if isinstance(v, str):
                    check_value(v, f"{where} {role}", "")
                    if self.parameters[v].kind not in (ROLE_KINDS[role], "other"):
                        raise NetworkError(
                            f"{where} {role} uses {v!r}, declared as a {self.parameters[v].kind}, not a"
                            f" {ROLE_KINDS[role]}"
                        )
                else:
                    check_value(v, f"{where} {role}", "" if role == "magnitude" else "positive")
                    if role == "magnitude" and float(v) < 0:
                        raise ParameterError(f"{where} magnitude must be >= 0 W, got {float(v):g}")

    def _check_floating(self) -> None:
        """Every connected group of nodes must reach a boundary or a supply-air element."""
        adj: dict[str, set[str]] = {n.name: set() for n in self.nodes}
        for r in self.resistors:
            for a, b in ((r.a, r.b), (r.b, r.a)):
                if a in adj:
                    adj[a].add(b)
        anchored = {s.node for s in self.supply_air}
        unvisited = set(adj)
        while unvisited:
            start = unvisited.pop()
            comp, stack, grounded = {start}, [start], False
            while stack:
                cur = stack.pop()
                grounded |= cur in anchored
                for nb in adj[cur]:
                    if nb in self.boundaries:
                        grounded = True
                    elif nb not in comp:
                        comp.add(nb)
                        stack.append(nb)
            unvisited -= comp
            if not grounded:
                raise NetworkError(
                    f"node(s) {', '.join(repr(c) for c in sorted(comp))} are floating: no resistor path to a boundary"
                    " temperature or supply-air element, so their temperature has no reference"
                )

    # ------------------------------------------------------------------ build
    def values(self, theta: Mapping[str, float] | None = None) -> dict[str, float]:
        """Every parameter's value given base values ``theta`` (defaults for the rest)."""
        return resolve(self.parameters, theta, self._tie_order)

    def state_space(self, theta: Mapping[str, float] | None = None) -> BilinearStateSpace:
        """Continuous-time bilinear state space for parameter values ``theta``.

        Pure: the network is not changed. Massless nodes are eliminated exactly.

        Parameters
        ----------
        theta : mapping of str to float, optional
            Base parameter values (SI); omitted ones take their declared default.

        Returns
        -------
        BilinearStateSpace
        """
        built = self._assemble(self.values(theta), float)
        return BilinearStateSpace(
            A=built.A,
            N=built.N,
            B=built.B,
            M=built.M,
            C=built.C,
            D=built.D,
            state_names=self.state_names,
            input_names=self.input_names,
            flow_names=self.flow_names,
            output_names=self.outputs,
            capacities=built.capacities,
            diffusion=built.diffusion,
        )

    def state_space_derivatives(
        self, theta: Mapping[str, float] | None, wrt: Sequence[str], log: bool = True
    ) -> list[StateSpaceDerivative]:
        """Exact derivatives of the state-space matrices with respect to base parameters.

        Computed by complex-step differentiation through the network assembly (including
        tied parameters and the elimination of massless nodes), which is exact to rounding
        error because no difference of nearly equal numbers is formed [1]_.

        Parameters
        ----------
        theta : mapping, optional
            Base parameter values at which to differentiate.
        wrt : sequence of str
            Base parameter names.
        log : bool
            If True, derivatives with respect to ``log(theta_j)`` (i.e. ``theta_j d/dtheta_j``).

        Returns
        -------
        list of StateSpaceDerivative
            One per name in ``wrt``: ``(dA, dN, dB, dM, dC, dD, dQ)`` (``dQ``: of the diffusion).

        References
        ----------
        .. [1] J. R. R. A. Martins, P. Sturdza, J. J. Alonso, "The complex-step derivative
           approximation", ACM Trans. Math. Software 29(3), 2003.
        """
        base = self.values(theta)
        out = []
        h = 1e-30
        for name in wrt:
            if name not in self.parameters:
                raise ParameterError(f"unknown parameter {name!r}; " + did_you_mean(name, self.parameters))
            if self.parameters[name].is_tied:
                raise ParameterError(f"parameter {name!r} is tied; differentiate with respect to its base")
            vals: dict[str, complex] = {k: v for k, v in base.items() if not self.parameters[k].is_tied}
            step = h * (vals[name] if log else 1.0)
            vals[name] = vals[name] + 1j * step
            vals = evaluate_ties(self.parameters, vals, self._tie_order)
            built = self._assemble(vals, complex)
            mats = (built.A, built.N, built.B, built.M, built.C, built.D, built.diffusion)
            out.append(StateSpaceDerivative(*(np.imag(m_) / h for m_ in mats)))
        return out

    @cached_property
    def _structure(self) -> dict:
        """Index arrays for :meth:`_assemble`, computed once per network (it is immutable)."""
        names = [n.name for n in self.nodes]
        idx = {n: i for i, n in enumerate(names)}
        iidx = {n: i for i, n in enumerate(self.input_names)}
        fidx = {f: k for k, f in enumerate(self.flow_names)}
        nn, p, nr = len(names), len(self.input_names), len(self.resistors)
        # G = L' diag(g) L (node Laplacian incl. the diagonal terms of boundary resistors) and
        # Gb = P' diag(g) E (node-to-input conductances), with g the resistor conductances
        L, P, E = np.zeros((nr, nn)), np.zeros((nr, nn)), np.zeros((nr, p))
        for k, r in enumerate(self.resistors):
            ia, ib = idx.get(r.a, -1), idx.get(r.b, -1)
            if ia >= 0 and ib >= 0:
                L[k, ia], L[k, ib] = 1.0, -1.0
            else:
                i = ia if ia >= 0 else ib
                L[k, i] = P[k, i] = 1.0
                E[k, iidx[r.a if ia < 0 else r.b]] = 1.0
        xs = np.array([idx[n] for n in self.node_state_names], dtype=int)
        zs = np.array([idx[n] for n in self.massless_names], dtype=int)
        out = [idx[o] for o in self.outputs]
        Cfull = np.zeros((len(out), nn))
        Cfull[np.arange(len(out)), out] = 1.0
        # heat-input gains and supply-air cp given as numbers are assembled once; those given
        # as parameter names are added per call
        heat = [(idx[nd], iidx[h.name], g) for h in self.heat_inputs for nd, g in h.split]
        air = [(fidx[s.flow], idx[s.node], iidx[s.temperature], s.cp) for s in self.supply_air]
        Gb_const = np.zeros((nn, p))
        for i, j, g in heat:
            if not isinstance(g, str):
                Gb_const[i, j] += float(g)
        Nf, Mf = np.zeros((len(fidx), nn, nn)), np.zeros((len(fidx), nn, p))
        for k, i, j, cp in air:
            if not isinstance(cp, str):
                Nf[k, i, i] -= float(cp)
                Mf[k, i, j] += float(cp)
        return {
            "nn": nn,
            "L": L,
            "P": P,
            "E": E,
            "res": [r.resistance for r in self.resistors],
            "heat": [h for h in heat if isinstance(h[2], str)],
            "air": [a for a in air if isinstance(a[3], str)],
            "Gb": Gb_const,
            "Nf": Nf,
            "Mf": Mf,
            "xs": xs,
            "zs": zs,
            "xx": np.ix_(xs, xs),
            "zz": np.ix_(zs, zs),
            "zx": np.ix_(zs, xs),
            "xz": np.ix_(xs, zs),
            "Cx": Cfull[:, xs],
            "Cz": Cfull[:, zs],
            "cap": [nd.capacity for nd in self.nodes if nd.capacity is not None],
            "dist": [[(idx[nd], g) for nd, g in d.gains] for d in self.disturbances],
        }

    def _assemble(self, vals: Mapping[str, float | complex], dtype: type) -> BilinearMatrices:
        """The state space's matrices and per-state constants from resolved parameter values."""
        st = self._structure

        def v(x: Value) -> float | complex:
            return vals[x] if isinstance(x, str) else float(x)

        xs, zs = st["xs"], st["zs"]
        res = np.array([v(r) for r in st["res"]], dtype)
        _check_positive(res, st["res"], "resistor")
        # the conductance (Laplacian) among nodes and from nodes to inputs, with the numeric heat
        # gains: the one compiled assembly, also the compiled costs' (imported here: a network is
        # declared without loading numba)
        from rczone.kernels.problem import conductances

        G, Gb = conductances(st["L"], st["P"], st["E"], st["Gb"], res)
        for i, j, gain in st["heat"]:
            Gb[i, j] += v(gain)
        Nf, Mf = st["Nf"], st["Mf"]
        if st["air"] or dtype is not float:
            Nf, Mf = Nf.astype(dtype), Mf.astype(dtype)
            for k, i, j, cp in st["air"]:
                Nf[k, i, i] -= v(cp)
                Mf[k, i, j] += v(cp)
        # energy balance: Cap dT/dt = -G T + Gb u + sum_k m_k (Nf_k T + Mf_k u)
        # the disturbances' heat flows (W per unit of their latent states) enter like inputs
        Gd, F, qd = self._latent_blocks(vals, dtype, st["nn"])
        p, nl = Gb.shape[1], Gd.shape[1]
        Axx, Bx = -G[st["xx"]], np.concatenate([Gb[xs], Gd[xs]], axis=1)
        C, D = st["Cx"].astype(dtype), np.zeros((st["Cx"].shape[0], p + nl), dtype)
        if zs.size:
            # Kron reduction: z = Kz x + Lz u  from  0 = -G_zx x - G_zz z + Gb_z u
            Gzz = G[st["zz"]]
            KL = np.linalg.solve(Gzz, np.concatenate([-G[st["zx"]], Gb[zs], Gd[zs]], axis=1))
            Kz, Lz = KL[:, : xs.size], KL[:, xs.size :]
            Axz = -G[st["xz"]]
            Axx = Axx + Axz @ Kz
            Bx = Bx + Axz @ Lz
            C = C + st["Cz"] @ Kz
            D = D + st["Cz"] @ Lz
        cap = np.array([v(c) for c in st["cap"]], dtype)
        _check_positive(cap, st["cap"], "capacity")
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):  # refused just below,
            inv = (1.0 / cap)[:, None]  # in one line, not after numpy's overflow warnings
        tiny = np.flatnonzero(~np.isfinite(inv[:, 0]))
        if tiny.size:
            i = int(tiny[0])
            raise ParameterError(
                f"capacity {st['cap'][i]!r} = {cap.real[i]:g} J/K is too small (its inverse overflows);"
                " give a capacity in J/K"
            )
        Nx = np.ascontiguousarray(Nf[:, xs][:, :, xs] * inv[None])  # fancy indexing leaves it strided
        A, B, M = Axx * inv, Bx[:, :p] * inv, Mf[:, xs] * inv[None]
        if not nl:
            return BilinearMatrices(A, Nx, B, M, C, D, cap, np.zeros(xs.size))
        # state (x, s): dx = (A x + Bd s + B u) dt, ds = F s dt + noise; y = C x + Cd s + D u
        nx = xs.size
        A = np.block([[A, Bx[:, p:] * inv], [np.zeros((nl, nx), dtype), F]])
        Nx = np.concatenate([Nx, np.zeros((Nx.shape[0], nx, nl), dtype)], axis=2)
        Nx = np.concatenate([Nx, np.zeros((Nx.shape[0], nl, nx + nl), dtype)], axis=1)
        B = np.concatenate([B, np.zeros((nl, p), dtype)])
        M = np.concatenate([M, np.zeros((M.shape[0], nl, p), dtype)], axis=1)
        C = np.concatenate([C, D[:, p:]], axis=1)
        cap = np.concatenate([cap, np.full(nl, np.nan)])
        diffusion = np.concatenate([np.zeros(nx, dtype), qd])
        return BilinearMatrices(A, Nx, B, M, C, D[:, :p], cap, diffusion)

    def _latent_blocks(
        self, vals: Mapping[str, float | complex], dtype: type, nn: int
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(Gd, F, qd)``: node heat flow per latent state (W, shape (nn, nl)), drift, diffusion."""

        def v(x: Value) -> float | complex:
            return vals[x] if isinstance(x, str) else float(x)

        nl = len(self.latent_state_names)
        Gd, F, qd = np.zeros((nn, nl), dtype), np.zeros((nl, nl), dtype), np.zeros(nl, dtype)
        k = 0
        for d, entries in zip(self.disturbances, self._structure["dist"], strict=True):
            sigma = v(d.magnitude)
            if (sigma.real if isinstance(sigma, complex) else sigma) < 0:
                raise ParameterError(f"disturbance {d.name!r}: magnitude must be >= 0 W, got {sigma:g}")
            ell = v(d.length_scale)
            period = None if d.period is None else v(d.period)
            for x, what in ((ell, "length scale"), (period, "period")):
                if x is not None and not (x.real if isinstance(x, complex) else x) > 0:
                    raise ParameterError(f"disturbance {d.name!r}: {what} must be > 0 s, got {x:g}")
            sde = latent_sde(d.kind, ell, period)
            m = sde.F.shape[0]
            F[k : k + m, k : k + m] = sde.F
            qd[k : k + m] = sde.qc
            for i, g in entries:
                Gd[i, k] += sigma * v(g)
            k += m
        return Gd, F, qd

    @cached_property
    def conductance_form(self) -> ConductanceForm | None:
        """The network as constant arrays and parameter lists, for compiled assembly.

        ``G = L' diag(1/R) L``, ``Gb = P' diag(1/R) E + Gb0``, ``A = -G / c``, ``B = Gb / c``,
        ``N_k = Nf_k / c``, ``M_k = Mf_k / c`` (rows divided by the capacities); the heat-input
        gains that are parameters (a circuit's shares, a window's aperture) are listed in
        ``gains`` and add their values to ``Gb``. Available when every node is capacitive (no Kron
        reduction) and supply-air ``cp`` are numbers; None otherwise.
        """
        st = self._structure
        if st["zs"].size or st["air"] or self.disturbances:
            return None
        return ConductanceForm(
            L=st["L"],
            P=st["P"],
            E=st["E"],
            Gb0=st["Gb"],
            Nf=st["Nf"],
            Mf=st["Mf"],
            resistances=tuple(st["res"]),
            capacities=tuple(st["cap"]),
            output_state=tuple(self.state_names.index(o) for o in self.outputs),
            gains=tuple((int(i), int(j), g) for i, j, g in st["heat"]),
        )

    def conductance_values(self, theta: Mapping[str, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
        """``(R, c)``: resistor values and capacities (state order) for ``theta``, ties resolved."""
        vals = self.values(theta)
        form = self.conductance_form
        if form is None:
            raise NetworkError(f"network {self.name!r} has no plain conductance form (massless nodes?)")
        r = np.array([vals[x] if isinstance(x, str) else float(x) for x in form.resistances])
        c = np.array([vals[x] if isinstance(x, str) else float(x) for x in form.capacities])
        _check_positive(r, form.resistances, "resistor")
        _check_positive(c, form.capacities, "capacity")
        return r, c

    def replace_parameters(self, parameters: Iterable[Parameter]) -> RCNetwork:
        """A copy of the network with some parameter declarations replaced or added."""
        params = dict(self.parameters)
        for p in parameters:
            params[p.name] = p
        return RCNetwork(
            self.name,
            self.nodes,
            self.boundaries,
            self.resistors,
            params.values(),
            self.heat_inputs,
            self.supply_air,
            self.outputs,
            self.description,
            disturbances=self.disturbances,
        )
