"""The parameters through which the inputs act: what a collinear group of inputs leaves undetermined.

The excitation itself is a property of the data (:mod:`rczone.data.excitation`); this module maps
it to the model's parameters for the identifiability verdicts.
"""

from __future__ import annotations

from collections.abc import Sequence


def parameters_of(network, inputs: Sequence[str]) -> dict[str, tuple[str, ...]]:
    """The parameters through which each input acts: the gains of a heat input, the resistances to a boundary.

    Parameters
    ----------
    network : RCNetwork
    inputs : sequence of str
        Input names.

    Returns
    -------
    dict of parameter name to the inputs it belongs to
    """
    from rczone.diagnostics.identifiability import parameter_boundaries

    out: dict[str, list[str]] = {}
    for h in network.heat_inputs:
        if h.name in inputs:
            for _, g in h.split:
                if isinstance(g, str) and g in network.parameters:
                    out.setdefault(g, []).append(h.name)
    for name in network.parameters:
        for b in parameter_boundaries(network, name):
            if b in inputs:
                out.setdefault(name, []).append(b)
    return {k: tuple(v) for k, v in out.items()}
