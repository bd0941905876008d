"""Fuzzing the public API (issue 39): every exported function, hostile values of each argument type.

The third hostile campaign went through the Python API where the first two went through the
command line, and found the API passing what the command refused: negative seeds to NumPy, a
trillion prediction steps to the filter, NaN initial temperatures to the simulation (1,439 NaN
cells returned without a word), a column of text to pandas. Here each exported function gets, for
one argument at a time, values drawn from its type's hostile set (negative, huge, non-finite,
bool, text, wrong container), the others valid. The only outcomes allowed are a result without a
NaN where a number is reported, or an :class:`~rczone.errors.RczoneError` whose message is one
line; a traceback from NumPy, pandas, numba or the sampler is a defect.

The integer strategies are all refused (a valid seed would start a full fit); the cheap
functions (simulate, predict, smooth, the constructors) also get valid but extreme values. A few
dozen examples per function keep ``make test`` quick; the ``slow`` round runs more.
"""

from __future__ import annotations

import math
import os

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import rczone
from rczone.errors import RczoneError

#: Examples per function: a few dozen keep ``make test`` quick; ``RCZONE_FUZZ_EXAMPLES=500`` runs a long round.
EXAMPLES = int(os.environ.get("RCZONE_FUZZ_EXAMPLES", "15"))
FAST = settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck), database=None)
LONG = settings(
    max_examples=max(400, EXAMPLES), deadline=None, suppress_health_check=list(HealthCheck), database=None
)

MODEL = "TiTe"


def _frame(n: int = 48) -> pd.DataFrame:
    """Data simulated from the model itself (sampled every 5 min), so every value is plausible."""
    t = np.arange(n) * 300.0
    to = 5.0 + 3.0 * np.sin(t / 7e3)
    frame = pd.DataFrame({"time": t, "To": to, "Ti": 20.0 + 0.0 * t})
    states = rczone.simulate(MODEL, frame)
    frame["Ti"] = states["Ti"].to_numpy() + 0.01 * np.cos(t / 900.0)
    return frame


DATA = _frame()


def _fitted():
    from rczone.models import load_model

    return load_model(MODEL).with_values({}, {"sigma_v": 0.05, "sigma_w_Ti": 0.002}, method="ml")


FITTED = _fitted()

# ---- hostile values by type -------------------------------------------------------------------

bad_integers = st.one_of(
    st.integers(-(10**30), -1),
    st.integers(2**63, 10**40),
    st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(),
    st.text(max_size=5),
    st.just([1]),
)
any_floats = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([0.0, -0.0, 1e-300, -1.0, 1e308, -1e308, 5e-324]),
    st.booleans(),
    st.text(max_size=5),
)
names = st.one_of(
    st.sampled_from(["Ti", "Te", "To", "Ci", "Rie", "sigma_v", "time", ""]), st.text(max_size=6)
)
hostile_mappings = st.one_of(
    st.dictionaries(names, any_floats, max_size=3),
    st.lists(any_floats, max_size=2),
    st.text(max_size=4),
    st.integers(),
)
hostile_texts = st.one_of(st.text(max_size=12), st.sampled_from(["", " ", "\n", "ml\x00", "ZOH", "open"]))
hostile_sequences = st.one_of(
    st.lists(names, max_size=3), names, st.lists(st.integers(), max_size=2), st.integers()
)


def _column(kind: str, n: int) -> object:
    return {
        "text": ["x"] * n,
        "numeric text": [str(v) for v in range(n)],
        "bool": [True] * n,
        "nan": [math.nan] * n,
        "inf": [math.inf] * n,
        "huge": [1e308] * n,
        "dates": pd.date_range("2020-01-01", periods=n, freq="5min"),
        "complex": [1 + 1j] * n,
        "objects": [None] * n,
    }[kind]


column_kinds = st.sampled_from(
    ["text", "numeric text", "bool", "nan", "inf", "huge", "dates", "complex", "objects"]
)


@st.composite
def hostile_frames(draw) -> pd.DataFrame:
    """The model's data with one column spoiled, a time axis broken, or rows cut."""
    frame = DATA.copy()
    what = draw(st.sampled_from(["column", "time", "rows", "cell"]))
    if what == "column":
        frame[draw(st.sampled_from(["To", "Ti", "time"]))] = _column(draw(column_kinds), len(frame))
    elif what == "time":
        t = frame["time"].to_numpy().copy()
        i = draw(st.integers(1, len(t) - 1))
        change = draw(st.sampled_from(["gap", "repeat", "reverse", "nan", "negative"]))
        if change == "gap":
            t[i:] += 1e15
        elif change == "repeat":
            t[i] = t[i - 1]
        elif change == "reverse":
            t = t[::-1].copy()
        elif change == "nan":
            t[i] = math.nan
        else:
            t -= 1e20
        frame["time"] = t
    elif what == "rows":
        frame = frame.iloc[: draw(st.integers(0, 2))]
    else:
        col = draw(st.sampled_from(["To", "Ti"]))
        i = draw(st.integers(0, len(frame) - 1))
        frame.loc[i, col] = draw(st.sampled_from([math.nan, math.inf, -math.inf, 1e308, -1e308]))
    return frame


# ---- what an outcome may be -------------------------------------------------------------------


def _numbers(obj: object, skip: tuple[str, ...] = ()):
    """Every float in a nested result (``to_dict()``), but those under the keys ``skip``."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            if k not in skip:
                yield from _numbers(v, skip)
    elif isinstance(obj, (list, tuple)):
        for v in obj:
            yield from _numbers(v, skip)
    elif isinstance(obj, (float, np.floating)):
        yield float(obj)


def _no_nan_in_table(frame: pd.DataFrame) -> None:
    """A table of scores: a score that does not exist is missing (``pd.NA``), never a float NaN."""
    floats = [c for c in frame.columns if frame[c].dtype == float]
    assert np.isfinite(frame[floats].to_numpy(float)).all(), f"NaN or inf in a table of results:\n{frame}"


def result_or_one_line(call):
    """Call; a result must hold no NaN where it reports a number, an error must be rczone's and one line."""
    try:
        out = call()
    except RczoneError as exc:
        text = str(exc)
        assert text and "\n" not in text, text
        return None
    if isinstance(out, rczone.Calibration):  # a flagged fit may lack standard errors, never estimates
        assert all(math.isfinite(v) for v in _numbers(out.result.estimates)), out.result.estimates
        return out
    if isinstance(out, pd.DataFrame):  # a simulation: every node at every sample
        assert np.isfinite(out.to_numpy(float)).all(), f"non-finite values in the result:\n{out}"
    elif hasattr(out, "to_dict"):  # its scores (a series may leave samples it does not predict empty)
        bad = [v for v in _numbers(out.to_dict()) if not math.isfinite(v)]
        assert not bad, f"non-finite scores in {type(out).__name__}: {out.to_dict()}"
    if isinstance(out, rczone.Prediction):  # no band: no coverage (None), never NaN
        assert out.coverage is None or np.isfinite(out.coverage).all(), out.coverage
        assert np.isfinite(out.rmse_K).all() and np.isfinite(out.max_abs_K).all()
    if type(out).__name__ == "HorizonScores":
        _no_nan_in_table(out.to_frame())
    return out


# ---- the functions ----------------------------------------------------------------------------


@FAST
@given(st.sampled_from(["seed", "n_starts", "draws", "tune", "chains"]), bad_integers)
def test_fit_refuses_hostile_integers(name, value):
    kw = {name: value}
    if name in ("draws", "tune", "chains"):  # the sampler's own options
        kw = {"method": "mcmc", "options": {name: value}}
    result_or_one_line(lambda: rczone.fit(MODEL, DATA, checks=False, **kw))


@FAST
@given(
    st.sampled_from(["method", "optimizer", "noise", "hold", "free", "constants", "bounds", "fixed"]),
    st.data(),
)
def test_fit_refuses_hostile_options(name, data):
    strategy = {
        "free": hostile_sequences,
        "constants": hostile_mappings,
        "bounds": st.dictionaries(names, st.tuples(any_floats, any_floats), max_size=2),
        "fixed": st.dictionaries(
            st.sampled_from(["Ci", "Ce", "Rie", "Rea", "sigma_v"]), any_floats, min_size=4
        ),
    }.get(name, hostile_texts)
    value = data.draw(strategy)
    if name == "fixed" and all(isinstance(v, float) and math.isfinite(v) and v > 0 for v in value.values()):
        value = {**value, "Rie": math.nan}  # a valid fixed set would start a fit
    if name == "constants" and isinstance(value, dict) and all(k == "To" for k in value):
        value = {**value, "Te": 1.0}
    result_or_one_line(lambda: rczone.fit(MODEL, DATA, n_starts=1, checks=False, **{name: value}))


@FAST
@given(hostile_frames())
def test_fit_refuses_hostile_data_or_flags_it(frame):
    result_or_one_line(lambda: rczone.fit(MODEL, frame, method="ls", n_starts=1, checks=False))


@FAST
@given(hostile_frames())
def test_simulate_and_predict_on_hostile_data(frame):
    result_or_one_line(lambda: rczone.simulate(MODEL, frame))
    result_or_one_line(lambda: rczone.predict(FITTED, frame, steps=1))


@FAST
@given(
    st.one_of(
        st.dictionaries(st.sampled_from(["Ti", "Te", "To", "x"]), any_floats, min_size=1), hostile_mappings
    )
)
def test_simulate_hostile_initial_states(x0):
    result_or_one_line(lambda: rczone.simulate(MODEL, DATA, x0=x0))


@FAST
@given(st.one_of(bad_integers, st.integers(48, 10**15)))
def test_predict_hostile_steps(steps):
    result_or_one_line(lambda: rczone.predict(FITTED, DATA, steps=steps))


@FAST
@given(st.sampled_from(["initial_state", "hold"]), hostile_texts)
def test_predict_hostile_options(name, value):
    result_or_one_line(lambda: rczone.predict(FITTED, DATA, **{name: value}))


@FAST
@given(
    st.dictionaries(
        st.sampled_from(["sigma_v", "sigma_w_Ti"]), st.sampled_from([0.0, 1e-300, 1e7, 1e300]), min_size=1
    )
)
def test_predict_and_smooth_with_hostile_noise_levels(noise):
    from rczone.models import load_model

    def both():
        zm = load_model(MODEL).with_values({}, noise, method="ml")
        rczone.predict(zm, DATA, steps=1)
        return rczone.smooth(zm, DATA)

    result_or_one_line(both)


@FAST
@given(st.sampled_from(["seed", "sigma", "model_error", "operating_point", "free"]), st.data())
def test_diagnose_refuses_hostile_values(name, data):
    strategy = {
        "seed": bad_integers,
        "sigma": st.one_of(st.floats(allow_nan=True).filter(lambda v: not 0 < v < 1e3), st.text(max_size=3)),
        "model_error": st.one_of(
            st.floats(allow_nan=True).filter(lambda v: not 0 <= v < 1e3), st.text(max_size=3)
        ),
        "operating_point": hostile_texts.filter(lambda v: v not in ("auto", "model", "fit")),
        "free": hostile_sequences.filter(lambda v: v not in ([], "")),
    }[name]
    kw = {"operating_point": "model", name: data.draw(strategy)}
    result_or_one_line(lambda: rczone.diagnose(MODEL, DATA, **kw))


@FAST
@given(st.sampled_from(["seed", "criterion", "alpha", "n_starts"]), st.data())
def test_select_models_refuses_hostile_values(name, data):
    strategy = {
        "seed": bad_integers,
        "n_starts": bad_integers,
        "criterion": hostile_texts.filter(lambda v: v.strip().lower() not in ("bic", "aic")),
        "alpha": st.one_of(st.floats(allow_nan=True).filter(lambda v: not 0 < v < 1), st.text(max_size=3)),
    }[name]
    result_or_one_line(lambda: rczone.select_models(["Ti", MODEL], DATA, **{name: data.draw(strategy)}))


@FAST
@given(st.sampled_from(["hours", "min_hold", "initial", "band", "actuate"]), st.data())
def test_design_test_refuses_hostile_values(name, data):
    strategy = {
        "hours": any_floats.filter(lambda v: not (isinstance(v, float) and 0.5 <= v <= 48)),
        "min_hold": any_floats.filter(lambda v: not (isinstance(v, float) and 1 <= v <= 600)),
        "initial": any_floats.filter(lambda v: not (isinstance(v, float) and -50 <= v <= 60)),
        "band": st.tuples(any_floats, any_floats),
        "actuate": st.dictionaries(names, st.tuples(any_floats, any_floats), max_size=2),
    }[name]
    kw = {"actuate": {"To": (0.0, 10.0)}, "hours": 1.0}
    kw[name] = data.draw(strategy)
    result_or_one_line(lambda: rczone.design_test(MODEL, **kw))


@FAST
@given(bad_integers, hostile_texts, hostile_texts)
def test_virtual_night_refuses_hostile_values(seed, season, mode):
    result_or_one_line(lambda: rczone.VirtualNight(season, mode, seed))


@FAST
@given(
    st.sampled_from(["matern32", "matern52", "periodic"]),
    st.one_of(any_floats, names),
    st.one_of(any_floats, names),
    st.one_of(any_floats, st.none()),
)
def test_latent_force_refuses_what_a_model_file_refuses(kind, magnitude, length_scale, period):
    result_or_one_line(
        lambda: rczone.LatentForce(
            "d", kind, "Ti", magnitude=magnitude, length_scale=length_scale, period=period
        )
    )


@FAST
@given(hostile_texts)
def test_load_model_and_load_data_refuse_hostile_names(text):
    result_or_one_line(lambda: rczone.load_model(text))
    result_or_one_line(lambda: rczone.load_data(text))


@FAST
@given(hostile_frames(), st.sampled_from([None, 1, 3]))
def test_predict_open_loop_and_smooth_on_hostile_data(frame, steps):
    """A model without noise levels too: no band, so no coverage (None), never NaN."""
    result_or_one_line(lambda: rczone.predict(MODEL, frame))
    result_or_one_line(lambda: rczone.predict(FITTED, frame, steps=steps))
    result_or_one_line(lambda: rczone.smooth(FITTED, frame))


@FAST
@given(
    st.one_of(
        hostile_sequences, hostile_texts, st.lists(st.one_of(st.integers(), st.just("open")), max_size=3)
    ),
    st.one_of(st.none(), hostile_texts, st.sampled_from(["1h", "3h", "4h", "1d", "0s", "-1h"])),
    st.booleans(),
)
def test_score_horizons_refuses_hostile_values(horizons, warmup, baselines):
    result_or_one_line(
        lambda: rczone.score_horizons(FITTED, DATA, horizons=horizons, warmup=warmup, baselines=baselines)
    )


@FAST
@given(hostile_frames(), st.sampled_from(["open", "1,open", "3"]))
def test_score_horizons_on_hostile_data(frame, horizons):
    result_or_one_line(
        lambda: rczone.score_horizons(MODEL if horizons == "open" else FITTED, frame, horizons=horizons)
    )


@FAST
@given(
    st.one_of(
        st.dictionaries(
            st.sampled_from(["Ci", "Ce", "Rie", "Rea", "x"]), st.one_of(any_floats, names), max_size=3
        ),
        hostile_mappings,
    ),
    st.one_of(
        st.none(),
        st.dictionaries(st.sampled_from(["sigma_v", "sigma_w_Ti", "x0_Te"]), any_floats),
        hostile_mappings,
    ),
)
def test_model_values_refuse_hostile_values(theta, noise):
    from rczone.models import load_model

    result_or_one_line(lambda: load_model(MODEL).with_values(theta, noise))


anything = st.one_of(any_floats, names, bad_integers, st.none(), hostile_mappings, hostile_sequences)


@FAST
@given(st.sampled_from(["Node", "Resistor", "HeatInput", "SupplyAir", "Parameter", "RCNetwork"]), st.data())
def test_network_constructors_refuse_hostile_values(cls, data):
    value = data.draw(anything)
    make = {
        "Node": lambda: rczone.Node("T", value),
        "Resistor": lambda: rczone.Resistor("T", "To", value),
        "HeatInput": lambda: rczone.HeatInput("Q", value),
        "SupplyAir": lambda: rczone.SupplyAir("T", cp=value),
        "Parameter": lambda: rczone.Parameter("C", "capacitance", value),
        "RCNetwork": lambda: rczone.RCNetwork("n", value, ["To"], [rczone.Resistor("T", "To", "R")]),
    }[cls]
    result_or_one_line(make)


@FAST
@given(st.one_of(bad_integers, st.integers(51, 10**9), hostile_texts, st.lists(hostile_texts, max_size=3)))
def test_multizone_refuses_hostile_rooms(rooms):
    from rczone.models.multizone import multizone

    result_or_one_line(lambda: multizone(rooms))


@FAST
@given(st.sampled_from(["FitSettings", "TrendLog", "BuiltinNight", "model_to_toml"]), st.data())
def test_settings_sources_and_model_files_refuse_hostile_values(what, data):
    value = data.draw(anything)
    make = {
        "FitSettings": lambda: rczone.FitSettings(
            **{data.draw(st.sampled_from(["method", "seed", "n_starts", "noise", "hold", "free"])): value}
        ),
        "TrendLog": lambda: rczone.TrendLog(value),
        "BuiltinNight": lambda: rczone.BuiltinNight(value),
        "model_to_toml": lambda: rczone.model_to_toml(value),
    }[what]
    result_or_one_line(make)


#: A valid method record's fields (the built-in ML's), one of which the fuzz test makes hostile.
METHOD_FIELDS = {
    "name": "fuzzed",
    "title": "a fuzzed method",
    "kernel": "ml",
    "stochastic": True,
    "objective": "negative log-likelihood",
    "rmse_kind": "one-step",
    "run": lambda problem, options, rng: None,
}


@FAST
@given(st.sampled_from(["register_method", "register_controller", "register_emulator", "Method"]), st.data())
def test_plug_in_registrations_refuse_hostile_values(what, data):
    """A registry takes what it can run later, or refuses in one line; nothing is left registered."""
    from rczone.control.registry import unregister_controller
    from rczone.emulators.registry import unregister_emulator

    name, value = data.draw(st.one_of(names, anything)), data.draw(anything)
    make = {
        "register_method": lambda: rczone.register_method(value),
        "register_controller": lambda: rczone.register_controller(name, value),
        "register_emulator": lambda: rczone.register_emulator(name, value),
        "Method": lambda: rczone.Method(
            **{**METHOD_FIELDS, data.draw(st.sampled_from(sorted(METHOD_FIELDS))): value}
        ),
    }[what]
    try:
        result_or_one_line(make)
    finally:
        if isinstance(name, str):
            unregister_controller(name)
            unregister_emulator(name)


@pytest.mark.slow
@LONG
@given(hostile_frames())
def test_simulate_and_predict_on_hostile_data_long(frame):
    result_or_one_line(lambda: rczone.simulate(MODEL, frame))
    result_or_one_line(lambda: rczone.predict(FITTED, frame, steps=1))
