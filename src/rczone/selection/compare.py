"""Fit candidate models to the same data and choose one.

Every candidate is fitted by maximum likelihood (the Kalman filter of its stochastic model,
:func:`rczone.calibration.calibrate` with ``method="ml"``) on the *same* samples: the longest
stretch where every input of every candidate is known. For each fit:

* ``log L`` at the estimate, ``k`` free parameters (noise levels included), ``n`` observed
  outputs. By default the process noise of *every* state is estimated (``noise="all"``), as in
  Bacher & Madsen's stochastic models: a state whose diffusion is held at a guess cannot absorb
  what the model misses there, which shows in the innovations and the likelihood
  (``noise="measured"``: only the measured states', the default of ``rczone fit``);
* ``AIC = 2 k - 2 log L`` and ``BIC = k log n - 2 log L`` [2]_ [3]_;
* the whiteness of its standardized innovations (:mod:`rczone.postfit.innovations`);
* for every pair where one model is nested in the other (detected by
  :func:`rczone.selection.nesting.nesting`, never assumed), the likelihood-ratio test
  ``2 (log L_rich - log L_simple)`` against ``chi2(d)`` (and the chi-bar-squared p-value of the
  boundary restrictions beside it; see the nesting module).

Two ways of choosing:

* by an information criterion (``rule="bic"``, default, or ``"aic"``): the smallest;
* **forward selection** (``forward=True``, Bacher & Madsen 2011 [1]_): start from the candidate
  with the fewest parameters (the best-fitting one when several tie); fit the *smallest
  extensions* of the current model among the candidates (those it is nested in, with no other
  candidate in between); take the one with the highest likelihood; keep it when the
  likelihood-ratio test rejects the current model at level ``alpha``, and stop otherwise. Only
  the models the path reaches are fitted.

Either way the chosen model should have white innovations; the result says when it does not
(the candidates then all miss something).

A richer model's likelihood cannot be below that of a model nested in it; when its fit ends
there, its search missed the optimum, and the fit is repeated from the simpler model's estimates
(carried over by :func:`rczone.selection.nesting.realize`, held inside the search box) and the
better of the two kept.

References
----------
.. [1] P. Bacher, H. Madsen, "Identifying suitable models for the heat dynamics of buildings",
   Energy and Buildings 43 (2011) 1511-1522, section 4.
.. [2] H. Akaike, "A new look at the statistical model identification", IEEE Trans. Automatic
   Control 19 (1974) 716-723.
.. [3] G. Schwarz, "Estimating the dimension of a model", Annals of Statistics 6 (1978) 461-464.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
import pandas as pd
from scipy.special import chdtrc

from rczone.calibration import Calibration, ModelLike, as_model, calibrate, complete_stretch, frame_from
from rczone.calibration.dataset import ignored_channels
from rczone.errors import DataError, ParameterError, did_you_mean
from rczone.estimation.fit import default_free
from rczone.estimation.freeset import ADD, resolve_free
from rczone.estimation.settings import FitSettings
from rczone.models import ZoneModel
from rczone.network.stochastic import MEASUREMENT_NOISE, PROCESS_NOISE, kind_of, process_noise_name, target_of
from rczone.results import Result
from rczone.results.verdict import EXIT_UNTRUSTED
from rczone.selection.coupling import (
    Basis,
    VuongTest,
    check_measured,
    comparison_basis,
    conditional_logliks,
    vuong_test,
)
from rczone.selection.nesting import Nesting, nesting, realize

#: Ways of choosing among the candidates.
RULES = ("bic", "aic")
#: Which process-noise levels are estimated: of every state, or of the measured states only.
NOISE = ("all", "measured")
#: A richer model's log-likelihood may fall this far below a nested simpler one's before its fit is retried.
LOGLIK_TOLERANCE = 1e-3


@dataclass(frozen=True, eq=False)
class Candidate:
    """One candidate model fitted by ML.

    Attributes
    ----------
    name : str
    calibration : Calibration
    n_obs : int
        Observed output values the likelihood is over (with a conditional basis: target values).
    retried : bool
        The first fit ended below the likelihood of a simpler model nested in this one, and the
        fit was repeated from that model's estimates (the better of the two is kept).
    terms : ndarray, shape (N,), optional
        With a conditional basis (:mod:`rczone.selection.coupling`): the per-sample log-density
        of the target outputs given the neighbours' measurements; :attr:`loglik` is their sum.
    """

    name: str
    calibration: Calibration
    n_obs: int
    retried: bool = False
    terms: np.ndarray | None = None

    @property
    def trustworthy(self) -> bool:
        """Whether the candidate's fit carries no flag (its verdict)."""
        return bool(self.calibration.verdict.trustworthy)

    @property
    def flag_reasons(self) -> str:
        """Why the fit is flagged, in words ("" when it is not)."""
        return "; ".join(self.calibration.verdict.reasons) if not self.trustworthy else ""

    @property
    def fit_loglik(self) -> float:
        """``log L`` of the fit at the estimate, of all the model's outputs."""
        return float(self.calibration.result.llf)

    @property
    def loglik(self) -> float:
        """``log L`` the candidates are compared on: the fit's, or the conditional one of the targets."""
        return self.fit_loglik if self.terms is None else float(self.terms.sum())

    @property
    def n_params(self) -> int:
        """Free parameters, noise levels included."""
        return len(self.calibration.result.names)

    @property
    def aic(self) -> float:
        return 2.0 * self.n_params - 2.0 * self.loglik

    @property
    def bic(self) -> float:
        return self.n_params * math.log(self.n_obs) - 2.0 * self.loglik

    def criterion(self, rule: str) -> float:
        return self.aic if rule == "aic" else self.bic

    def to_dict(self) -> dict:
        r = self.calibration.result
        inn = self.calibration.innovations
        return {
            "loglik": self.loglik,
            "loglik_fit": self.fit_loglik,
            "n_params": self.n_params,
            "aic": self.aic,
            "bic": self.bic,
            "innovations": inn.to_dict() if inn is not None else None,
            "parameters": {n: r.estimates[n] for n in r.names},
            "std_errors": {n: r.std_errors[n] for n in r.names},
            "units": {n: e.unit for n, e in r.parameters.items()},
            # the fit's verdict (its flags, data, robust errors and, for the selected model with
            # held-out data, the held-out checks), as passed_over and exit_code read it
            "trustworthy": self.trustworthy,
            "flags": list(self.calibration.verdict.reasons),
            "verdict": self.calibration.verdict.to_dict(),
            "retried_from_simpler": self.retried,
        }


@dataclass(frozen=True)
class LikelihoodRatioTest:
    """The likelihood-ratio test of a simpler model nested in a richer one.

    Attributes
    ----------
    simple, rich : str
    nesting : Nesting
    statistic : float
        ``2 (log L_rich - log L_simple)`` (negative when the richer fit missed its optimum).
    df : int
    p_value : float
        ``P(chi2(df) > statistic)``: conservative at the boundary, the one used to decide.
    p_value_chi_bar : float
        The chi-bar-squared p-value for independent boundary restrictions (Self & Liang 1987).
    """

    simple: str
    rich: str
    nesting: Nesting
    statistic: float
    df: int
    p_value: float
    p_value_chi_bar: float

    def rejects(self, alpha: float) -> bool:
        """Whether the richer model fits significantly better at level ``alpha``."""
        return self.p_value < alpha

    def to_dict(self) -> dict:
        return {
            "simple": self.simple,
            "rich": self.rich,
            "restriction": self.nesting.describe(),
            "correspondence": dict(self.nesting.correspondence),
            "statistic": self.statistic,
            "df": self.df,
            "p_value": self.p_value,
            "p_value_chi_bar": self.p_value_chi_bar,
        }


def chi_bar_sf(statistic: float, df: int, n_boundary: int) -> float:
    """``P(X > statistic)`` for ``X ~ sum_i C(s, i) 2^-s chi2(df - s + i)``, ``s = min(n_boundary, df)``.

    The asymptotic law of the likelihood-ratio statistic when ``s`` of the ``df`` restrictions
    put a parameter on the boundary of its domain and the information matrix separates them
    (Self & Liang 1987, case 5); ``chi2(0)`` is a point mass at 0.
    """
    s = min(max(n_boundary, 0), df)
    x = max(statistic, 0.0)
    total = 0.0
    for i in range(s + 1):
        k = df - s + i
        tail = float(chdtrc(k, x)) if k > 0 else float(x <= 0.0)
        total += math.comb(s, i) / 2.0**s * tail
    return total


def likelihood_ratio_test(simple: Candidate, rich: Candidate, nest: Nesting) -> LikelihoodRatioTest:
    """The test of ``simple`` against ``rich`` (``simple`` nested in ``rich`` by ``nest``)."""
    stat = 2.0 * (rich.fit_loglik - simple.fit_loglik)
    return LikelihoodRatioTest(
        simple.name,
        rich.name,
        nest,
        stat,
        nest.df,
        float(chdtrc(nest.df, max(stat, 0.0))),
        chi_bar_sf(stat, nest.df, nest.n_boundary),
    )


@dataclass(frozen=True, eq=False, repr=False)
class Selection(Result):
    """The candidates, the tests between nested pairs, and the chosen model.

    Attributes
    ----------
    candidates : dict of str to Candidate
        Every fitted candidate, in the order given.
    tests : tuple of LikelihoodRatioTest
        Every nested pair among the fitted candidates.
    selected : str
    rule : {"bic", "aic", "forward"}
    alpha : float
        Level of the tests.
    path : tuple of str
        Forward selection: the models accepted in turn (else just the selected one).
    steps : tuple of dict
        Forward selection: per step, the current model, the extensions tried, the best and its
        test's p-value.
    not_fitted : tuple of str
        Candidates a forward selection never reached.
    passed_over : dict of str to str
        Candidates that scored better (criterion) or were the best extension (forward) but whose
        fits are flagged, with the flags in words: a flagged fit never wins silently. The selected
        model is flagged only when every candidate is.
    samples : dict
        The common stretch: ``n`` samples, ``start_s``, ``end_s``, ``n_obs`` observed outputs.
    basis : Basis, optional
        What the likelihoods are of: every candidate's outputs (``basis.given`` empty), or the
        common outputs conditional on the neighbours' measurements (:mod:`rczone.selection.coupling`).
    vuong : tuple of VuongTest
        With a conditional basis: Vuong's test of every pair of candidates not nested in each other.
    data_label : str
        The data's name, for titles.
    source : str
        The data as the user named them (a path), for the command line printed to refit.
    noise : str
        The process-noise placement the candidates were fitted with.
    fit_args : tuple of str
        The further ``rczone fit`` arguments that reproduce a candidate's fit alone (the column
        map, constants, hold, starts, seed), as the command line was given them.
    model_specs : dict of str to str
        What names each candidate on the command line (``--model``), when it is not its label
        (a model file).
    ignored_channels : tuple of str
        Channels the data's column map mapped that no candidate uses.
    holdout : HorizonScores or None
        The selected model's scores on data held out of the selection (``--holdout``); None without.
        Set by :func:`with_held_out`, which also puts their checks into the selected model's
        verdict (and so into :attr:`exit_code`), as ``rczone fit --holdout`` does.
    """

    candidates: Mapping[str, Candidate]
    tests: tuple[LikelihoodRatioTest, ...]
    selected: str
    rule: str
    alpha: float
    path: tuple[str, ...]
    steps: tuple[dict, ...] = ()
    not_fitted: tuple[str, ...] = ()
    passed_over: Mapping[str, str] = field(default_factory=dict)
    samples: Mapping[str, float] = field(default_factory=dict)
    basis: Basis | None = None
    vuong: tuple[VuongTest, ...] = ()
    data_label: str = "data"
    source: str = ""
    noise: str = "all"
    fit_args: tuple[str, ...] = ()
    model_specs: Mapping[str, str] = field(default_factory=dict)
    ignored_channels: tuple[str, ...] = ()
    holdout: Any = None

    @property
    def best(self) -> Candidate:
        """The selected candidate."""
        return self.candidates[self.selected]

    @property
    def exit_code(self) -> int:
        """0, or 3 when the selected model's fit is flagged (its verdict, held-out checks included)."""
        return 0 if self.best.calibration.verdict.trustworthy else EXIT_UNTRUSTED

    def _repr_line(self) -> str:
        return f"{self.selected} selected of {len(self.candidates)} candidates on {self.data_label} ({self.rule})"

    def summary_lines(self) -> list:
        """What ``rczone select`` prints after fitting the candidates."""
        from rich.markup import escape

        from rczone.selection.text import selection_lines, verdict_lines

        held = []
        if self.holdout is not None:  # the selected model's held-out scores and the checks it passed
            held = [*self.holdout.summary_lines(), *(escape(x) for x in self.held_out_evidence().notes)]
        return [*selection_lines(self), *held, *verdict_lines(self)]

    def held_out_evidence(self):
        """The held-out checks of the selected model (:func:`rczone.postfit.evidence.held_out_evidence`); None without."""
        if self.holdout is None:
            return None
        if self.best.calibration.evidence is not None:
            return self.best.calibration.evidence
        from rczone.postfit.evidence import held_out_evidence

        return held_out_evidence(self.holdout, self.best.calibration.innovations)

    def table(self) -> list[dict]:
        """One row per fitted candidate: log L, k, AIC, BIC and their differences to the best, whiteness."""
        aic0 = min(c.aic for c in self.candidates.values())
        bic0 = min(c.bic for c in self.candidates.values())
        rows = []
        for name, c in self.candidates.items():
            inn = c.calibration.innovations
            rows.append(
                {
                    "model": name,
                    "log L": c.loglik,
                    "k": c.n_params,
                    "AIC": c.aic,
                    "dAIC": c.aic - aic0,
                    "BIC": c.bic,
                    "dBIC": c.bic - bic0,
                    "Ljung-Box p": inn.ljung_box_p if inn is not None else None,
                    "white": ("yes" if inn.white else "no") if inn is not None else "n/a",
                    "selected": "<-" if name == self.selected else "",
                    "passed over": "flagged" if name in self.passed_over else "",
                }
            )
        return rows

    def to_frame(self) -> pd.DataFrame:
        """:meth:`table` as a frame indexed by model."""
        return pd.DataFrame(self.table()).set_index("model")

    def to_dict(self) -> dict:
        """What ``rczone select --json`` writes."""
        return {
            "data": self.data_label,
            "selected": self.selected,
            "rule": self.rule,
            "alpha": self.alpha,
            "samples": dict(self.samples),
            "basis": self.basis.describe() if self.basis is not None else "joint",
            "targets": list(self.basis.targets) if self.basis is not None else None,
            "models": {n: c.to_dict() for n, c in self.candidates.items()},
            "passed_over": dict(self.passed_over),
            "tests": [{"kind": "likelihood-ratio", **t.to_dict()} for t in self.tests]
            + [v.to_dict(self.alpha) for v in self.vuong],
            "forward": {"path": list(self.path), "steps": list(self.steps)}
            if self.rule == "forward"
            else None,
            "not_fitted": list(self.not_fitted),
            "selected_white": bool(self.best.calibration.innovations.white)
            if self.best.calibration.innovations is not None
            else None,
            "exit_code": self.exit_code,
            "ignored_channels": list(self.ignored_channels),
            **(
                {"holdout": {**self.holdout.to_dict(), "evidence": self.held_out_evidence().to_dict()}}
                if self.holdout is not None
                else {}
            ),
        }


def with_held_out(sel: Selection, scores) -> Selection:
    """``sel`` with the selected model's held-out scores, and their checks in its verdict.

    The held-out checks (:mod:`rczone.postfit.evidence`: band coverage per horizon, the
    baselines, the innovations) enter the selected fit's verdict as they enter ``rczone fit
    --holdout``'s, so a selection whose model fails them is flagged (:attr:`Selection.exit_code`
    3) and says which check failed.

    Parameters
    ----------
    sel : Selection
    scores : HorizonScores
        The selected model's scores on the held-out part
        (:func:`rczone.workflow.holdout.score_held_out`).

    Returns
    -------
    Selection
        A new selection; the other candidates are unchanged (only the selected one is scored).
    """
    from rczone.calibration.calibration import with_holdout

    best = dataclasses.replace(sel.best, calibration=with_holdout(sel.best.calibration, scores))
    candidates = {n: best if n == sel.selected else c for n, c in sel.candidates.items()}
    return dataclasses.replace(sel, candidates=candidates, holdout=scores)


def common_stretch(models: Sequence[ZoneModel], frame: pd.DataFrame, constants) -> pd.DataFrame:
    """The rows of ``frame`` in the longest stretch where every input of every model is known.

    Candidates that measure different outputs must be comparable on a conditional basis
    (:func:`rczone.selection.coupling.comparison_basis`, which raises otherwise).
    """
    comparison_basis({zm.label: zm.network for zm in models})
    signals = [zm.signals(frame, constants) for zm in models]
    u = np.column_stack([s[1] for s in signals])
    m = (
        np.column_stack([s[2] for s in signals])
        if any(s[2].size for s in signals)
        else np.zeros((len(frame), 0))
    )
    sl = complete_stretch(u, m, signals[0][3])
    if sl.stop - sl.start < 10:
        raise DataError(
            "fewer than 10 samples where every input of every candidate is known; check the data's gaps"
            " and the candidates' inputs"
        )
    return frame.iloc[sl].reset_index(drop=True)


def candidate_free(network, noise: str = "all") -> tuple[str, ...]:
    """The free parameters of a candidate: the ML default, with every state's process noise for ``"all"``."""
    return default_free(network, "ml", noise=noise)


def parameter_names(network) -> set[str]:
    """Every name a candidate's fit can free or fix: its free R, C and gains, noise levels and initial states.

    Parameters
    ----------
    network : RCNetwork
    """
    from rczone.estimation.parameters import noise_parameter_names

    return {*network.free_parameter_names, *noise_parameter_names(network)}


class CandidateParameters(NamedTuple):
    """What one candidate's fit estimates and holds."""

    free: tuple[str, ...]  #: its free parameters
    fixed: dict  #: name -> value held (None: the model's)


def candidate_parameters(
    models: Mapping[str, ZoneModel], settings: FitSettings
) -> dict[str, CandidateParameters]:
    """Each candidate's free and fixed parameters: its ML default set with ``noise``, the ``+NAME`` it has, less the fixed it has.

    The rule is ``rczone fit``'s (:func:`rczone.estimation.freeset.resolve_free`), applied to each
    candidate with the names it has; a name no candidate has is an error with the close names.

    Parameters
    ----------
    models : mapping of str to ZoneModel
        The candidates by name.
    settings : FitSettings
        Its ``noise`` (process noise on every state or on the measured ones), its ``free``
        (``"+NAME"`` entries added to the default free sets) and its ``fixed`` (parameters held at
        a value, None: the model's).

    Returns
    -------
    dict of str to CandidateParameters
    """
    free, fixed, noise = tuple(settings.free or ()), dict(settings.fixed), settings.noise
    replaced = [n for n in free if not n.startswith(ADD)]
    if replaced:
        raise ParameterError(
            f"select adds parameters to each candidate's own free set: write {ADD}{replaced[0]}"
            f" (--free {ADD}{replaced[0]}); the candidates' free sets cannot be replaced by one list"
        )
    names = {n: parameter_names(zm.network) for n, zm in models.items()}
    known = set().union(*names.values())
    for name in [*(n[len(ADD) :] for n in free), *fixed]:
        if name not in known:
            raise ParameterError(f"no candidate has a parameter {name!r}; " + did_you_mean(name, known))
    out = {}
    for c, zm in models.items():
        own = {k: v for k, v in fixed.items() if k in names[c]}
        added = [n for n in free if n[len(ADD) :] in names[c]]
        own_settings = FitSettings(method="ml", noise=noise, free=added or None, fixed=own)
        out[c] = CandidateParameters(resolve_free(zm.network, own_settings), own)
    return out


def family_candidates(columns: Sequence[str], *, extended: bool = False) -> list[str]:
    """The Bacher & Madsen family with the options the data can drive (``Ph``, ``Ps``, ``Q``, ``m`` and ``Ts``).

    Parameters
    ----------
    columns : sequence of str
        The data's columns.
    extended : bool
        Every base of the family (:func:`rczone.models.library.family_bases`, for forward
        selection, which fits only the steps it takes) instead of the five classic ones.

    Returns
    -------
    list of str
    """
    from rczone.models.library import FAMILY, family_bases, parse_name

    opts = [o for o, col in (("heater", "Ph"), ("solar", "Ps"), ("gain", "Q")) if col in columns]
    if "m" in columns and "Ts" in columns:
        opts.append("air")
    out = []
    for base in family_bases() if extended else FAMILY:
        name = "+".join((base, *opts))
        try:
            parse_name(name)
        except ParameterError:  # a solar part without solar data
            continue
        out.append(name)
    return out


def select_models(
    models: Sequence[ModelLike],
    frame: pd.DataFrame,
    settings: FitSettings | None = None,
    *,
    rule: str = "bic",
    forward: bool = False,
    alpha: float = 0.05,
    progress: Callable[[str], None] | None = None,
    **overrides: Any,
) -> Selection:
    """Fit the candidate ``models`` to ``frame`` by ML and choose one (see the module notes).

    Parameters
    ----------
    models : sequence of model
        At least two: built-in names, model files or :class:`~rczone.models.ZoneModel`.
    frame : DataFrame
        As for :func:`rczone.calibration.calibrate`.
    settings : FitSettings, optional
        The fits' settings, carried whole to every candidate's fit by ML (its method is ML
        whatever it says); default ``FitSettings(noise="all")``: process noise on every state, as
        likelihood-ratio tests and information criteria need a well specified noise model
        (Bacher & Madsen 2011). Its ``free`` entries are ``"+NAME"`` additions to every candidate
        that has the parameter (a name no candidate has is an error), its ``fixed`` and ``bounds``
        apply to the candidates that have the parameter (a name no candidate has is an error).
    rule : {"bic", "aic"}
        Information criterion (without ``forward``).
    forward : bool
        Forward selection by likelihood-ratio tests from the simplest candidate.
    alpha : float
        Level of the likelihood-ratio tests.
    progress : callable, optional
        Called with the name of each model before it is fitted; when it also has
        ``advance(done, total)`` (:class:`rczone.cli.progress.Reporter`), each fit tells it how far
        its search is.
    **overrides
        Fields of :class:`~rczone.estimation.settings.FitSettings` replacing those of ``settings``.

    References
    ----------
    .. [1] P. Bacher, H. Madsen, "Identifying suitable models for the heat dynamics of buildings",
       Energy and Buildings 43(7), 2011, 1511-1522.
    """
    settings = FitSettings.of(settings or FitSettings(noise="all"), **overrides)
    constants, noise = settings.constants or None, settings.noise
    if rule not in RULES:
        raise ParameterError(f"rule must be one of {RULES}, got {rule!r}")
    if not 0 < alpha < 1:
        raise ParameterError(f"alpha must be in (0, 1), got {alpha!r}")
    if noise not in NOISE:
        raise ParameterError(f"noise must be one of {NOISE}, got {noise!r}")
    zms = [as_model(m) for m in models]
    if len(zms) < 2:
        raise ParameterError("model selection needs at least two candidate models")
    names = [zm.label for zm in zms]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ParameterError(f"candidate {dup[0]!r} is given twice")
    by_name = dict(zip(names, zms))
    ignored = ignored_channels(frame)
    basis = comparison_basis({n: zm.network for n, zm in by_name.items()})
    if basis.conditional:
        if forward:
            raise ParameterError(
                f"the candidates measure different outputs and are compared {basis.describe()};"
                " forward selection moves between nested models of the same outputs: use a criterion"
            )
        check_measured(by_name, frame_from(frame), constants, basis)
    frame = common_stretch(zms, frame_from(frame), constants)
    own = candidate_parameters(by_name, settings)
    free = {n: own[n].free for n in by_name}
    bounds = dict(settings.bounds)
    known = {p for names_ in free.values() for p in names_}
    for b in bounds:
        if b not in known:
            raise ParameterError(
                f"bounds given for {b!r}, which no candidate estimates; {did_you_mean(b, known)}"
            )
    nests = _Nestings(by_name, free)
    fitted: dict[str, Candidate] = {}

    def fit_one(name: str) -> Candidate:
        if name in fitted:
            return fitted[name]
        if progress is not None:
            progress(name)

        def run(zm: ZoneModel) -> Calibration:
            box = {k: v for k, v in bounds.items() if k in free[name]}
            return calibrate(
                zm,
                frame,
                settings,
                method="ml",
                free=free[name],
                bounds=box,
                fixed=own[name].fixed or {},
                progress=progress if hasattr(progress, "advance") else None,
            )

        cal = run(by_name[name])
        simpler = [fitted[a] for a in fitted if nests.get(a, name) is not None]
        retried = False
        if simpler:
            best = max(simpler, key=lambda c: c.fit_loglik)
            if cal.result.llf < best.fit_loglik - LOGLIK_TOLERANCE:
                # below a special case of itself: the search missed the optimum; start where the simpler one is
                again = run(_warm_start(by_name[name], best, nests.get(best.name, name)))
                retried = True
                if again.result.llf > cal.result.llf:
                    cal = again
        fitted[name] = Candidate(name, cal, int(np.isfinite(cal.open_loop.error).sum()), retried)
        return fitted[name]

    order = sorted(names, key=lambda n: len(free[n]))
    steps: list[dict] = []
    passed_over: dict[str, str] = {}
    if forward:
        fewest = len(free[order[0]])
        first = [fit_one(n) for n in order if len(free[n]) == fewest]
        current = max(first, key=lambda c: c.loglik).name
        path = [current]
        while True:
            smallest = nests.smallest_extensions(current, path)
            if not smallest:
                break
            tried = [fit_one(b) for b in smallest]
            # a flagged fit (a parameter at a bound, a flat profile, ...) cannot be accepted: the
            # best sound extension is tested instead, and a flagged best is refused, not taken
            sound = [c for c in tried if c.trustworthy]
            best = max(sound or tried, key=lambda c: c.loglik)
            test = likelihood_ratio_test(fitted[current], best, nests.get(current, best.name))
            accept = test.rejects(alpha) and best.trustworthy
            flagged = {c.name: c.flag_reasons for c in tried if not c.trustworthy}
            passed_over.update(flagged)
            steps.append(
                {
                    "from": current,
                    "tried": [c.name for c in tried],
                    "best": best.name,
                    "statistic": test.statistic,
                    "df": test.df,
                    "p_value": test.p_value,
                    "accepted": accept,
                    "refused_flagged": bool(test.rejects(alpha) and not best.trustworthy),
                    "flagged": flagged,
                }
            )
            if not accept:
                break
            current = best.name
            path.append(current)
        selected, rule_used = current, "forward"
    else:
        for n in order:
            fit_one(n)
        if basis.conditional:
            measured = _condition(fitted, frame, basis, constants)
        ranked = sorted(fitted.values(), key=lambda c: c.criterion(rule))
        pick = next((c for c in ranked if c.trustworthy), ranked[0])
        # better-scoring candidates whose fits are flagged are passed over, and the table says so
        passed_over.update({c.name: c.flag_reasons for c in ranked[: ranked.index(pick)]})
        selected = pick.name
        path, rule_used = [selected], rule
    tests = tuple(
        likelihood_ratio_test(fitted[a], fitted[b], nest)
        for a in fitted
        for b in fitted
        if a != b and (nest := nests.get(a, b)) is not None
    )
    vuong = ()
    if basis.conditional:
        vuong = tuple(
            vuong_test(
                a,
                b,
                fitted[a].terms,
                fitted[b].terms,
                fitted[a].n_params,
                fitted[b].n_params,
                basis.describe(),
                measured,
            )
            for i, a in enumerate(names)
            for b in names[i + 1 :]
            if nests.get(a, b) is None and nests.get(b, a) is None
        )
    t = frame["time"].to_numpy(float)
    cands = {n: fitted[n] for n in names if n in fitted}
    return Selection(
        cands,
        tests,
        selected,
        rule_used,
        alpha,
        tuple(path),
        tuple(steps),
        tuple(n for n in names if n not in fitted),
        passed_over,
        {
            "n": len(frame),
            "start_s": float(t[0]),
            "end_s": float(t[-1]),
            "n_obs": next(iter(cands.values())).n_obs,
        },
        basis,
        vuong,
        noise=noise,
        ignored_channels=ignored,
    )


class _Nestings:
    """The nestings between candidates, found when first asked for (:func:`rczone.selection.nesting.nesting`).

    With many candidates (the extended family has 60 bases) most pairs are never needed: forward
    selection asks only about the steps it takes. When every candidate is a family model with the
    same options, the smallest extensions of a model are the candidates one part richer
    (:func:`rczone.models.library.family_extensions`) that the structural rule confirms; otherwise
    they are found among all candidates.
    """

    def __init__(self, models: Mapping[str, ZoneModel], free: Mapping[str, Sequence[str]]) -> None:
        from rczone.models.library import family_extensions, is_family_name

        self.models, self.free = models, free
        self.cache: dict[tuple[str, str], Nesting | None] = {}
        opts = {n.partition("+")[2] for n in models}
        self.family = len(opts) == 1 and all(is_family_name(n) for n in models)
        self.steps = family_extensions if self.family else None

    def get(self, simple: str, rich: str) -> Nesting | None:
        """How ``simple`` is nested in ``rich`` under the candidates' free parameters, or None."""
        key = (simple, rich)
        if key not in self.cache:
            a, b = self.models[simple], self.models[rich]
            self.cache[key] = nesting(
                a.network, b.network, self.free[simple], self.free[rich], a.theta, b.theta
            )
        return self.cache[key]

    def smallest_extensions(self, current: str, exclude: Sequence[str]) -> list[str]:
        """The candidates ``current`` is nested in with no other candidate in between."""
        if self.steps is not None:
            return [
                b
                for b in self.steps(current)
                if b in self.models and b not in exclude and self.get(current, b)
            ]
        ext = [b for b in self.models if b != current and b not in exclude and self.get(current, b)]
        return [b for b in ext if not any(self.get(c, b) for c in ext if c != b)]


def _condition(fitted: dict[str, Candidate], frame: pd.DataFrame, basis: Basis, constants) -> np.ndarray:
    """Put on every fitted candidate its per-sample conditional log-densities (in place of the dict).

    Returns the samples with a target value.
    """
    terms, measured = conditional_logliks(
        {n: c.calibration for n, c in fitted.items()}, frame, basis, constants
    )
    cols = frame[list(basis.targets)].to_numpy(float)
    n_obs = int(np.isfinite(cols[measured]).sum())
    for n, c in fitted.items():
        fitted[n] = dataclasses.replace(c, terms=terms[n], n_obs=n_obs)
    return measured


def _warm_start(zm: ZoneModel, simpler: Candidate, nest: Nesting) -> ZoneModel:
    """``zm`` with its start values at the estimates of a fitted simpler model nested in it (inside the bounds)."""
    source = simpler.calibration.model
    values = realize(nest, {**source.theta, **source.noise}, dict(zm.theta))
    theta = {}
    for k, v in values.items():
        p = zm.network.parameters.get(k)
        if p is None or p.is_tied:
            continue
        if p.bounds is not None:
            theta[k] = _inside(v, *p.bounds)
        elif not any(k == q for q, _ in nest.restriction):
            # (without declared bounds the box is relative to the start: a limit value would ruin it)
            theta[k] = v
    # a measurement noise at the data's floor (the lower bound of its box) starts 1 % above it:
    # a start on a bound is refused, and the richer model shares the simpler one's data and floor
    noise = {k: v * 1.01 for k, v in source.noise.items() if kind_of(k) == MEASUREMENT_NOISE}
    for k, v in source.noise.items():
        if kind_of(k) == PROCESS_NOISE:
            state = nest.node_map.get(target_of(k))
            if state is not None:
                noise[process_noise_name(state)] = v
    return zm.with_values(theta, {**zm.noise, **noise})


def _inside(v: float, lo: float, hi: float) -> float:
    """``v`` moved 1 % inside ``[lo, hi]`` (in log scale for a positive box)."""
    if lo > 0:
        return float(np.exp(np.clip(np.log(max(v, lo)), np.log(lo) + 0.01, np.log(hi) - 0.01)))
    pad = 0.01 * (hi - lo)
    return float(np.clip(v, lo + pad, hi - pad))
