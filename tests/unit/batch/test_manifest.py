"""Manifest parsing: defaults, per-zone overrides, generated nights, and one clear line per mistake."""

import tomllib

import pytest

from rczone.batch.manifest import parse_manifest, read_manifest
from rczone.errors import DataError
from rczone.estimation.settings import FitSettings
from rczone.workflow.datasource import BuiltinNight, TrendLog, VirtualNight


def parse(text, tmp_path):
    return parse_manifest(tomllib.loads(text), tmp_path / "m.toml")


def test_defaults_overrides_and_generated_nights(tmp_path):
    (tmp_path / "z.csv").write_text("time,Ti\n")
    m = parse(
        """
methods = ["ls", "ml"]
n_starts = 2
constants = { Q = 40.0 }

[[zone]]
id = "room"
data = "z.csv"
methods = ["map"]
free = ["Cr", "Rw"]

[[zone]]
id = "builtin"
data = "C"

[[generate]]
prefix = "g"
seasons = ["summer", "autumn"]
modes = ["forced"]
seeds = "3..5"
diagnose = false
""",
        tmp_path,
    )
    keys = [t.key for t in m.tasks]
    assert keys[:3] == ["room::map", "builtin::ls", "builtin::ml"]
    assert len(m.tasks) == 3 + 2 * 3 * 2 and len(m.zones) == 2 + 6
    room = m.tasks[0]
    assert room.source == TrendLog(str((tmp_path / "z.csv").resolve()), None)
    assert room.settings == FitSettings(
        method="map", free=("Cr", "Rw"), n_starts=2, constants={"Q": 40.0}, checks=False, profiles=False
    )
    assert m.tasks[1].source == BuiltinNight("C")  # a built-in data set by name
    gen = [t for t in m.tasks if t.zone == "g-autumn-forced-4"]
    assert [t.method for t in gen] == ["ls", "ml"] and gen[0].source == VirtualNight("autumn", "forced", 4)
    assert gen[0].source.label == "virtual:autumn/forced/4" and room.source.label == "z.csv"
    assert not gen[0].diagnose and room.diagnose


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ('modle = "x"\n[[zone]]\nid="a"\ndata="C"', r"unknown key 'modle'; did you mean 'model'"),
        (
            '[[zone]]\nid="a"\ndata="C"\nmethod = ["ls"]',
            r"zone 1: unknown key 'method'; did you mean 'methods'",
        ),
        ('methods = ["lsq"]\n[[zone]]\nid="a"\ndata="C"', r"unknown method 'lsq'; did you mean 'ls'"),
        ('model = "second-order-papr"\n[[zone]]\nid="a"\ndata="C"', r"did you mean 'second-order-paper'"),
        ('[[zone]]\nid="a"\ndata="C"\n[[zone]]\nid="a"\ndata="C"', r"duplicate zone id 'a'"),
        ('[[zone]]\ndata="C"', r"needs an id"),
        ('[[zone]]\nid="a"', r"exactly one of data"),
        (
            '[[zone]]\nid="a"\nvirtual={season="autum", seed=1}',
            r"unknown season 'autum'; did you mean 'autumn'",
        ),
        ('[[generate]]\nseeds="9..2"', r"seeds must be a list of integers or a range"),
        (
            'n_starts = 0\n[[zone]]\nid="a"\ndata="C"',
            r"n_starts must be \"auto\" or an integer from 1 to 1000",
        ),
        ("", r"no zones"),
    ],
)
def test_bad_manifests(tmp_path, text, match):
    with pytest.raises(DataError, match=match):
        parse(text, tmp_path)


def test_unreadable_manifests(tmp_path):
    with pytest.raises(DataError, match="does not exist"):
        read_manifest(tmp_path / "nope.toml")
    (tmp_path / "bad.toml").write_text("[[zone]\n")
    with pytest.raises(DataError, match="not valid TOML"):
        read_manifest(tmp_path / "bad.toml")


@pytest.mark.parametrize(
    ("content", "match"),
    [
        ('methods = ["ls"]\n[[zone]]\nid = "caf\xe9"\ndata = "C"\n'.encode("latin-1"), r"is not UTF-8 text"),
        (b"a = " + b"[" * 5000 + b"]" * 5000, r"nested more than 32 levels"),
        (b"a = " + b"[" * 40 + b"]" * 40, r"nested more than 32 levels"),
        (b"a = " + b"{x = " * 60 + b"1" + b"}" * 60, r"nested more than 32 levels"),
        (b"seeds = 1" + b"0" * 5000, r"not valid TOML"),
    ],
    ids=["latin-1", "deep-arrays", "deep-arrays-40", "deep-inline-tables", "huge-integer"],
)
def test_hostile_manifest_files_are_one_line(tmp_path, content, match):
    """Issue 14, defect 6: Latin-1 and deeply nested manifests ended in tracebacks."""
    (tmp_path / "m.toml").write_bytes(content)
    with pytest.raises(DataError, match=match) as info:
        read_manifest(tmp_path / "m.toml")
    assert "\n" not in str(info.value)


def test_a_folder_in_place_of_the_manifest_is_one_line(tmp_path):
    (tmp_path / "m.toml").mkdir()
    with pytest.raises(DataError, match=r"manifest '.*m.toml' is a folder, not a file"):
        read_manifest(tmp_path / "m.toml")


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (
            '[[generate]]\nseeds = "0..100000000"',
            r"200,000,002 calibrations \(zones x methods\) exceed the limit of 200,000"
            r" \(rczone.batch.manifest.MAX_TASKS\)",
        ),
        (
            '[[generate]]\nseeds = "0..99999999999999999999999"',
            r"seeds must be a list of integers or a range",
        ),
        (
            'n_starts = 100000000\n[[zone]]\nid="a"\ndata="C"',
            r"n_starts must be \"auto\" or an integer from 1 to 1000",
        ),
        ('methods = ["ls", "ls"]\n[[zone]]\nid="a"\ndata="C"', r"methods lists a method twice"),
        ("zone = [1, 2]", r"write zones as \[\[zone\]\] tables"),
        ('zone = "a"', r"write zones as \[\[zone\]\] tables"),
        ('[[generate]]\nseasons = "autumn"', r"seasons must be a non-empty list"),
        ('[[generate]]\nmodes = ["forcd"]', r"unknown mode 'forcd'; did you mean 'forced'"),
        ("[[generate]]\nprefix = 3", r"prefix must be a non-empty string"),
        ('[[zone]]\nid="a"\ndata="a\\u0000b"', r"data must be a non-empty string"),
        ('[[zone]]\nid="a"\ndata=3', r"data must be a non-empty string"),
        ('columns = 3\n[[zone]]\nid="a"\ndata="C"', r"columns must be a non-empty string"),
        ('optimizer = ["x"]\n[[zone]]\nid="a"\ndata="C"', r"unknown optimizer"),
        (
            'constants = { Q = nan }\n[[zone]]\nid="a"\ndata="C"',
            r"constants must be a table of finite numbers",
        ),
        (
            'constants = { Q = true }\n[[zone]]\nid="a"\ndata="C"',
            r"constants must be a table of finite numbers",
        ),
        ('model = "mine.toml"\n[[zone]]\nid="a"\ndata="C"', r"model file 'mine.toml' does not exist"),
        ('model = 5\n[[zone]]\nid="a"\ndata="C"', r"model must be a non-empty string"),
        ('seed = -1\n[[zone]]\nid="a"\ndata="C"', r"seed must be a non-negative integer"),
        ('noise = "al"\n[[zone]]\nid="a"\ndata="C"', r"unknown noise 'al'; did you mean 'all'"),
    ],
)
def test_more_bad_manifests(tmp_path, text, match):
    """Issue 14, defects 6 and 11: wrong types and absurd sizes are one line, before any work."""
    with pytest.raises(DataError, match=match):
        parse(text, tmp_path)


def test_a_model_file_is_resolved_against_the_manifest_folder(tmp_path):
    from rczone.models import load_model, model_to_toml

    (tmp_path / "models").mkdir()
    text = model_to_toml(load_model("first-order"))
    (tmp_path / "models" / "mine.toml").write_text(text)
    m = parse('model = "models/mine.toml"\n[[zone]]\nid = "a"\ndata = "C"\nmethods = ["ls"]', tmp_path)
    assert m.tasks[0].model == str((tmp_path / "models" / "mine.toml").resolve())
    before = m.tasks[0].fingerprint
    (tmp_path / "models" / "mine.toml").write_text("# edited\n" + text)
    assert m.tasks[0].fingerprint != before  # an edited model file is a new task
    (tmp_path / "models" / "broken.toml").write_text("[network\n")
    with pytest.raises(DataError, match=r"zone 1 \(a\): .*broken.toml"):
        parse('[[zone]]\nid = "a"\ndata = "C"\nmodel = "models/broken.toml"', tmp_path)
