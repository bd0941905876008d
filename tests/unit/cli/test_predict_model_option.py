"""``rczone predict --model M DATA`` as other commands take the model (issue 37, item 9).

The positional form ``rczone predict M DATA`` stays; both give the same prediction, and a model
given twice, or none, is one line and exit 2.
"""

from __future__ import annotations

import json

import pytest

from rczone.cli.main import main


def _predict(args, tmp_path, name):
    out = tmp_path / f"{name}.json"
    assert main(["predict", *args, "--json", str(out)]) == 0
    return json.loads(out.read_text())


def test_the_model_by_option_predicts_as_the_model_by_position(tmp_path, capsys):
    by_position = _predict(["second-order", "B"], tmp_path, "position")
    by_option = _predict(["--model", "second-order", "B"], tmp_path, "option")
    assert by_option == by_position
    assert by_option["rmse_K"] > 0  # a real prediction, not two empty results


@pytest.mark.parametrize(
    "args, words",
    [
        (["--model", "second-order", "second-order", "B"], "give the model once"),
        (["B"], "needs a model and data"),
        ([], "needs a model and data"),
    ],
)
def test_a_model_given_twice_or_not_at_all_is_one_line(args, words, capsys):
    assert main(["predict", *args]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err
