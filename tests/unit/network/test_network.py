import numpy as np
import pytest

from rczone.errors import InputShapeError, NetworkError, ParameterError
from rczone.network import HeatInput, Node, Parameter, RCNetwork, Resistor, SupplyAir
from rczone.simulation import simulate

P = [
    Parameter("Cr", "capacitance", 2e5),
    Parameter("Cw", "capacitance", 5e6),
    Parameter("Rwin", "resistance", 0.12),
    Parameter("R1", "resistance", 0.004),
    Parameter("R2", "resistance", 0.006),
]


def second_order(**over):
    kw = dict(
        name="2nd",
        nodes=[Node("Ti", "Cr"), Node("Tw", "Cw")],
        boundaries=["To", "Tsd"],
        resistors=[Resistor("Ti", "To", "Rwin"), Resistor("Ti", "Tw", "R1"), Resistor("Tw", "Tsd", "R2")],
        parameters=P,
        heat_inputs=[HeatInput("Q", {"Ti": 1.0})],
        supply_air=[SupplyAir("Ti", "m", "Ts")],
    )
    kw.update(over)
    return RCNetwork(**kw)


def test_second_order_matrices_match_paper_eq4_written_by_hand():
    """SPEC eq. (4): Cr dTi = (To-Ti)/Rwin + (Tw-Ti)/R1 + m cp (Ts-Ti) + Q; Cw dTw = (Ti-Tw)/R1 + (Tsd-Tw)/R2."""
    Cr, Cw, Rwin, R1, R2, cp = 2e5, 5e6, 0.12, 0.004, 0.006, 1005.0
    ss = second_order().state_space()
    assert ss.input_names == ("To", "Tsd", "Ts", "Q") and ss.flow_names == ("m",)
    A = np.array([[-(1 / Rwin + 1 / R1) / Cr, 1 / (R1 * Cr)], [1 / (R1 * Cw), -(1 / R1 + 1 / R2) / Cw]])
    B = np.array([[1 / (Rwin * Cr), 0, 0, 1 / Cr], [0, 1 / (R2 * Cw), 0, 0]])
    N = np.array([[[-cp / Cr, 0], [0, 0]]])
    M = np.array([[[0, 0, cp / Cr, 0], [0, 0, 0, 0]]])
    np.testing.assert_allclose(ss.A, A, rtol=1e-14)
    np.testing.assert_allclose(ss.B, B, rtol=1e-14)
    np.testing.assert_allclose(ss.N, N, rtol=1e-14)
    np.testing.assert_allclose(ss.M, M, rtol=1e-14)
    np.testing.assert_array_equal(ss.C, [[1.0, 0.0]])
    Am, Bm = ss.matrices(0.1)
    np.testing.assert_allclose(Am, A + 0.1 * N[0], rtol=1e-14)
    np.testing.assert_allclose(Bm, B + 0.1 * M[0], rtol=1e-14)


def test_the_compiled_costs_assemble_the_same_hand_written_matrices():
    """One assembly: the compiled costs' ``assemble`` (kernels/problem.py) on the network's conductance
    form gives eq. (4) by hand, as ``state_space`` does through the same ``conductances``; and the
    complex-step path (complex resistances) differentiates it exactly: dA/dR1 by hand."""
    from rczone.kernels.arrays import ConductanceArrays
    from rczone.kernels.problem import assemble

    Cr, Cw, Rwin, R1, R2, cp = 2e5, 5e6, 0.12, 0.004, 0.006, 1005.0
    net = second_order()
    form = net.conductance_form
    res, cap = net.conductance_values()
    arrays = ConductanceArrays(
        form.L, form.P, form.E, form.Gb0, form.Nf, form.Mf, np.array(form.output_state)
    )
    A0, N, B0, M = assemble(arrays, res, cap)
    A = np.array([[-(1 / Rwin + 1 / R1) / Cr, 1 / (R1 * Cr)], [1 / (R1 * Cw), -(1 / R1 + 1 / R2) / Cw]])
    B = np.array([[1 / (Rwin * Cr), 0, 0, 1 / Cr], [0, 1 / (R2 * Cw), 0, 0]])
    np.testing.assert_allclose(A0, A, rtol=1e-14)
    np.testing.assert_allclose(B0, B, rtol=1e-14)
    np.testing.assert_allclose(N, [[[-cp / Cr, 0], [0, 0]]], rtol=1e-14)
    np.testing.assert_allclose(M, [[[0, 0, cp / Cr, 0], [0, 0, 0, 0]]], rtol=1e-14)
    (d,) = net.state_space_derivatives(None, ["R1"], log=False)
    dA = np.array([[1 / Cr, -1 / Cr], [-1 / Cw, 1 / Cw]]) / R1**2
    np.testing.assert_allclose(d.dA, dA, rtol=1e-12)
    np.testing.assert_array_equal(d.dB, np.zeros_like(B))


def test_massless_node_between_two_resistors_equals_their_series_sum():
    series = RCNetwork(
        "s",
        [Node("Ti", "C"), Node("Tmid", None)],
        ["To"],
        [Resistor("Ti", "Tmid", "Ra"), Resistor("Tmid", "To", "Rb")],
        [
            Parameter("C", "capacitance", 1e5),
            Parameter("Ra", "resistance", 0.01),
            Parameter("Rb", "resistance", 0.03),
        ],
        outputs=["Ti", "Tmid"],
    )
    single = RCNetwork(
        "1", [Node("Ti", "C")], ["To"], [Resistor("Ti", "To", 0.04)], [Parameter("C", "capacitance", 1e5)]
    )
    s1, s2 = series.state_space(), single.state_space()
    np.testing.assert_allclose(s1.A, s2.A, rtol=1e-14)
    np.testing.assert_allclose(s1.B, s2.B, rtol=1e-14)
    # the massless node's temperature divides the drop in proportion to the resistances
    np.testing.assert_allclose(s1.C[1], [0.75]) and np.testing.assert_allclose(s1.D[1], [0.25])


def test_massless_output_node_gives_feedthrough():
    net = RCNetwork(
        "air",
        [Node("Tair", None), Node("Tw", "Cw")],
        ["To"],
        [Resistor("Tair", "To", 0.1), Resistor("Tair", "Tw", 0.1)],
        [Parameter("Cw", "capacitance", 1e6)],
        heat_inputs=[HeatInput("Q", {"Tair": 1.0})],
    )
    ss = net.state_space()
    assert ss.state_names == ("Tw",) and ss.output_names == ("Tair",)
    np.testing.assert_allclose(ss.C, [[0.5]])
    np.testing.assert_allclose(ss.D, [[0.5, 0.05]])


def test_heat_split_and_parameter_gain():
    net = second_order(
        heat_inputs=[HeatInput("Qsol", {"Ti": 0.3, "Tw": "fw"})],
        parameters=[*P, Parameter("fw", "gain", 0.7)],
    )
    ss = net.state_space({"fw": 0.5})
    np.testing.assert_allclose(ss.B[:, -1], [0.3 / 2e5, 0.5 / 5e6])


def test_state_space_is_pure():
    net = second_order()
    a = net.state_space({"R1": 0.01}).A.copy()
    net.state_space({"R1": 0.5})
    np.testing.assert_array_equal(net.state_space({"R1": 0.01}).A, a)
    assert net.parameters["R1"].value == 0.004


@pytest.mark.parametrize(
    ("over", "exc", "match"),
    [
        ({"resistors": [Resistor("Ti", "Tx", "Rwin")]}, NetworkError, r"undeclared node 'Tx'"),
        ({"resistors": [Resistor("Ti", "Tow", "Rwin")]}, NetworkError, r"did you mean .*'To'"),
        ({"resistors": [Resistor("Ti", "To", "Rwn")]}, NetworkError, r"undeclared parameter 'Rwn'.*'Rwin'"),
        ({"resistors": [Resistor("Ti", "To", -1.0)]}, ParameterError, r"must be > 0"),
        ({"resistors": [Resistor("Ti", "Ti", "Rwin")]}, NetworkError, r"to itself"),
        ({"resistors": [Resistor("To", "Tsd", "Rwin")]}, NetworkError, r"two boundary"),
        (
            {"resistors": [Resistor("Ti", "To", "Rwin")]},
            NetworkError,
            r"'Tw' are floating",
        ),
        ({"nodes": [Node("Ti", "Cr"), Node("Ti", "Cw")]}, NetworkError, r"declared twice"),
        ({"nodes": [Node("Ti", "Rwin"), Node("Tw", "Cw")]}, NetworkError, r"declared as a resistance"),
        ({"heat_inputs": [HeatInput("Q", {"Tq": 1.0})]}, NetworkError, r"undeclared node 'Tq'"),
        ({"supply_air": [SupplyAir("Ti", "To", "Ts")]}, NetworkError, r"clashes"),
        ({"outputs": ["Tz"]}, NetworkError, r"output refers to undeclared node 'Tz'"),
        ({"nodes": [Node("Ti"), Node("Tw", "Cw")]}, NetworkError, r"massless node 'Ti'"),
        ({"parameters": [*P, P[0]]}, NetworkError, r"'Cr' is declared twice"),
    ],
)
def test_bad_networks(over, exc, match):
    with pytest.raises(exc, match=match):
        second_order(**over)


def test_state_space_rejects_unknown_parameter_with_suggestion():
    with pytest.raises(ParameterError, match=r"unknown parameter 'Rwim'.*did you mean 'Rwin'"):
        second_order().state_space({"Rwim": 0.1})
    with pytest.raises(ParameterError, match=r"must be > 0"):
        second_order().state_space({"Cr": -5.0})


@pytest.mark.parametrize(
    ("t", "u", "m", "match"),
    [
        (
            np.arange(5.0),
            np.zeros((4, 4)),
            np.zeros((5, 1)),
            r"u must have shape \(n_samples, 4\) = \(5, 4\)",
        ),
        (np.arange(5.0), np.zeros((5, 3)), np.zeros((5, 1)), r"columns \['To', 'Tsd', 'Ts', 'Q'\]"),
        (
            np.array([0.0, 60, 60, 120, 180]),
            np.zeros((5, 4)),
            np.zeros((5, 1)),
            r"strictly increasing: t\[2\]",
        ),
        (np.array([0.0, 60, 30, 120, 180]), np.zeros((5, 4)), np.zeros((5, 1)), r"strictly increasing"),
        (np.arange(5.0), np.zeros((5, 4)), None, r"pass m"),
        (np.arange(5.0), np.zeros((5, 4)), np.zeros((5, 2)), r"m must have shape"),
        (np.arange(5.0), np.full((5, 4), np.nan), np.zeros((5, 1)), r"column 'To' is not finite at sample 0"),
        (np.zeros((5, 1)), np.zeros((5, 4)), np.zeros((5, 1)), r"time must be a 1-D"),
    ],
)
def test_bad_simulation_inputs(t, u, m, match):
    with pytest.raises(InputShapeError, match=match):
        simulate(second_order().state_space(), t, u, m)


def test_bad_initial_state_shape():
    with pytest.raises(InputShapeError, match=r"x0 must have shape \(2,\)"):
        simulate(
            second_order().state_space(), np.arange(3.0), np.zeros((3, 4)), np.zeros((3, 1)), x0=np.zeros(3)
        )


def test_a_capacity_whose_inverse_overflows_is_one_error_without_numpy_warnings():
    import warnings

    from rczone.models import load_model

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's overflow warning would be raised here first
        with pytest.raises(ParameterError, match=r"capacity 'Ci' = 4\.9\d*e-324 J/K is too small"):
            load_model("Ti").with_values({"Ci": 5e-324}).network.state_space()
