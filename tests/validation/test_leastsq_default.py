"""The default LS fit (Gauss-Newton from a few starts) reaches the optimum of 32 L-BFGS starts on real data.

The cases of ``validation/own_building.py`` (the synthetic zone of an unshipped structure always; the
three real data sets where ../shared/data is present) fitted from the command line with
``--method ls``: the default search against ``--optimizer lbfgs --starts 32``, an independent search
(another local method, sixteen times the starts). The default must reach that optimum within the LS
tolerance (1e-5 of the cost, :data:`rczone.estimation.methods.REGISTRY`). Gauss-Newton is the default
where the problem packs into arrays (the synthetic zone, the LEEC classroom); the Bacher-Madsen and
Armadillo models free a solar aperture (a gain), which the compiled problem does not take, and keep
L-BFGS on the integrated squared error.
"""

from __future__ import annotations

import json

import pytest

from rczone.cli.main import main as rczone
from tests.shared_data import SHARED, require
from tests.validation.scripts import load_script

OWN = load_script("own_building")


def ls_fit(data, model, column_map, out, *extra: str) -> dict:
    args = [
        "fit",
        str(data),
        "--model",
        str(model),
        "--method",
        "ls",
        "--no-profiles",
        "--json",
        str(out),
        *extra,
    ]
    if column_map is not None:
        args += ["--columns", str(column_map)]
    rczone(args)
    return json.loads(out.read_text())


#: The default local method of each case.
DEFAULT = {
    "synthetic": "gauss-newton",
    "bacher_madsen_prbs": "lbfgs",
    "armadillo_pysip": "lbfgs",
    "leec_classroom_vav": "gauss-newton",
}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(DEFAULT))
def test_the_default_ls_fit_reaches_the_optimum_of_32_lbfgs_starts(tmp_path, name) -> None:
    if name == "synthetic":
        model, data = OWN.synthetic_data(tmp_path)
        column_map = None
    else:
        rel, cmap, mfile = OWN.REAL[name]
        data = SHARED / rel
        require(data, what=f"{name}: shared real data")
        model, column_map = OWN.HERE / "models" / mfile, OWN.HERE / "maps" / cmap
    default = ls_fit(data, model, column_map, tmp_path / "default.json")
    reference = ls_fit(
        data, model, column_map, tmp_path / "ref.json", "--optimizer", "lbfgs", "--starts", "32"
    )
    assert default["optimizer"] == DEFAULT[name] and reference["optimizer"] == "lbfgs"
    assert default["objective_value"] <= reference["objective_value"] * (1 + 1e-5), (default, reference)
