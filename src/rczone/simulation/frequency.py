"""Frequency response of the LTI case and the paper's model-order error measure [1]_.

References
----------
.. [1] Lin, Middelkoop, Barooah, IEEE CDC 2012, section III, eqs. (6)-(7).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from rczone.errors import InputShapeError, did_you_mean
from rczone.network.statespace import LinearStateSpace


@dataclass(frozen=True, eq=False)
class FrequencyResponse:
    """Complex responses ``H[k, i, j]`` from input j to output i at ``freq_hz[k]``."""

    freq_hz: np.ndarray
    H: np.ndarray
    input_names: tuple[str, ...]
    output_names: tuple[str, ...]

    def to_input(self, name: str, output: int = 0) -> np.ndarray:
        """Response from one input (or a summed group, see :meth:`summed`) to an output."""
        if name not in self.input_names:
            raise InputShapeError(f"no input {name!r}; " + did_you_mean(name, self.input_names))
        return self.H[:, output, self.input_names.index(name)]

    def summed(self, groups: Mapping[str, Sequence[str]]) -> FrequencyResponse:
        """Responses with groups of inputs summed into one (Lin et al. 2012, eq. (6), ``H_sd``).

        ``groups={"Tsd": ["Tf", "Tc", "Tn1", "Tn2", "Thw"]}`` replaces the five surrounding
        temperatures by their common-mode input ``Tsd``; other inputs are kept.
        """
        grouped = {n for names in groups.values() for n in names}
        for n in grouped:
            if n not in self.input_names:
                raise InputShapeError(f"cannot sum unknown input {n!r}; " + did_you_mean(n, self.input_names))
        names: list[str] = []
        cols: list[np.ndarray] = []
        placed: set[str] = set()
        for j, n in enumerate(self.input_names):
            if n in grouped:
                g = next(k for k, v in groups.items() if n in v)
                if g not in placed:
                    placed.add(g)
                    names.append(g)
                    cols.append(sum(self.H[:, :, self.input_names.index(x)] for x in groups[g]))
            else:
                names.append(n)
                cols.append(self.H[:, :, j])
        return FrequencyResponse(self.freq_hz, np.stack(cols, axis=2), tuple(names), self.output_names)


def frequency_response(ss: LinearStateSpace, freq_hz: np.ndarray) -> FrequencyResponse:
    """``H(j w) = C (j w I - A)^{-1} B + D`` at frequencies ``freq_hz`` (Hz).

    Parameters
    ----------
    ss : LinearStateSpace
        E.g. ``network.state_space(theta).lti(m=0.12)``.
    freq_hz : ndarray, shape (K,)

    Returns
    -------
    FrequencyResponse
    """
    f = np.atleast_1d(np.asarray(freq_hz, dtype=float))
    if f.ndim != 1 or np.any(f < 0) or not np.all(np.isfinite(f)):
        raise InputShapeError("freq_hz must be a 1-D array of finite non-negative frequencies")
    n = ss.n_states
    H = np.empty((f.size, ss.C.shape[0], ss.B.shape[1]), dtype=complex)
    eye = np.eye(n)
    for k, fk in enumerate(f):
        H[k] = ss.C @ np.linalg.solve(2j * np.pi * fk * eye - ss.A, ss.B) + ss.D
    return FrequencyResponse(f, H, ss.input_names, ss.output_names)


def gain_error(
    reference: FrequencyResponse, other: FrequencyResponse, du: Mapping[str, float], output: int = 0
) -> dict[str, np.ndarray]:
    """Weighted gain error ``e_i(w) = | |H_ref,i| - |H_i| | * du_i`` (Lin et al. 2012, eq. (7)).

    Parameters
    ----------
    reference, other : FrequencyResponse
        On the same frequency grid, with the inputs named in ``du``.
    du : mapping of input name to its largest variation in the data (K, W or kg/s).

    Returns
    -------
    dict of input name to ndarray of shape (K,)
        Error in the output's unit (K) at each frequency.
    """
    if reference.freq_hz.shape != other.freq_hz.shape or not np.allclose(reference.freq_hz, other.freq_hz):
        raise InputShapeError("both responses must be on the same frequency grid")
    return {
        name: np.abs(np.abs(reference.to_input(name, output)) - np.abs(other.to_input(name, output)))
        * float(d)
        for name, d in du.items()
    }
