"""What every result of rczone offers: the shared protocol and the per-parameter estimate record.

A result (a calibration, a prediction, an identifiability report, a test design, a model
selection, a batch summary) prints itself (:meth:`~rczone.results.protocol.Result.summary`: exactly
what the command line prints), serializes itself (``to_dict``: exactly what ``--json`` writes),
gives its table as a DataFrame (``to_frame``) and shows itself in a notebook (``_repr_html_``),
with a one-line ``repr``.
"""

from rczone.results.estimate import Estimate
from rczone.results.protocol import Result, json_number, render_plain

__all__ = ["Estimate", "Result", "json_number", "render_plain"]
