"""What ``rczone --help`` and a command's help show: the work's order, flags without type tags."""

from __future__ import annotations

import re

import pytest

from rczone.cli.main import WORKFLOW_ORDER, main


def help_text(args, capsys) -> str:
    try:
        code = main([*args, "--help"])
    except SystemExit as stop:
        code = stop.code
    assert code in (0, None)
    return capsys.readouterr().out


def test_commands_are_listed_in_the_order_of_the_work(capsys):
    text = help_text([], capsys)
    listed = [m.group(1) for m in re.finditer(r"^│ ([a-z-]+) ", text, re.M)]
    listed = [n for n in listed if not n.startswith("-")]
    assert listed == list(WORKFLOW_ORDER)


@pytest.mark.parametrize("command", [[], ["fit"], ["select"], ["design"], ["demo"]])
def test_no_flag_shows_a_bool_tag(command, capsys):
    text = help_text(command, capsys)
    assert "<bool>" not in text and "--help" in text


def test_design_limits_and_control_band_are_two_names(capsys):
    assert "--limits" in help_text(["design"], capsys)
    assert "--band" not in help_text(["design"], capsys)
    assert "--band" in help_text(["control-test"], capsys)
