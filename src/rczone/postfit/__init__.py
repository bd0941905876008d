"""The analyses of a fitted model on data: is the fit one to believe?

One module per analysis, each a statistic of a :class:`~rczone.estimation.FitResult` and the
:class:`~rczone.estimation.Dataset` it was fitted to (or scored on):

* :mod:`~rczone.postfit.innovations` -- the one-step prediction errors and their whiteness
  (autocorrelation, Ljung-Box, cumulative periodogram; Madsen 2007 [1]_, ch. 5);
* :mod:`~rczone.postfit.openloop` -- the open-loop simulation error and the Ljung-Box test of a
  residual series;
* :mod:`~rczone.postfit.robust` -- misspecification-robust (sandwich) standard errors
  (White 1982 [2]_);
* :mod:`~rczone.postfit.profiles` -- profiles of each R and C, estimates far from the
  construction, and the comparison of fits to different data (Raue et al. 2009 [3]_);
* :mod:`~rczone.postfit.evidence` -- the held-out evidence the verdict weighs: band coverage per
  horizon, the baselines, the held-out innovations (Ljung 1999 [4]_, sec. 16.6).

They fit nothing and import no calibration: :func:`rczone.calibration.calibrate` makes the
innovations, open-loop and robust analyses with the fit, and the checks made after it
(:mod:`rczone.workflow.checks`) add the profiles and the held-out evidence.

References
----------
.. [1] H. Madsen, *Time Series Analysis*, Chapman & Hall 2007.
.. [2] H. White, "Maximum likelihood estimation of misspecified models", Econometrica 50(1), 1982.
.. [3] A. Raue et al., "Structural and practical identifiability analysis of partially observed
   dynamical models by exploiting the profile likelihood", Bioinformatics 25(15), 2009.
.. [4] L. Ljung, *System Identification: Theory for the User*, 2nd ed., Prentice Hall 1999.
"""

from rczone.postfit.evidence import EvidenceCheck, HeldOutEvidence, held_out_evidence
from rczone.postfit.innovations import ResidualAnalysis, analyse_residuals, innovation_analysis
from rczone.postfit.openloop import OpenLoopError, ResidualTest, ljung_box, open_loop_error
from rczone.postfit.profiles import (
    Disagreement,
    ProfileCheck,
    compare_fits,
    far_from_construction,
    profile_checks,
)
from rczone.postfit.robust import RobustErrors, robust_errors

__all__ = [
    "Disagreement",
    "EvidenceCheck",
    "HeldOutEvidence",
    "OpenLoopError",
    "ProfileCheck",
    "ResidualAnalysis",
    "ResidualTest",
    "RobustErrors",
    "analyse_residuals",
    "compare_fits",
    "far_from_construction",
    "held_out_evidence",
    "innovation_analysis",
    "ljung_box",
    "open_loop_error",
    "profile_checks",
    "robust_errors",
]
