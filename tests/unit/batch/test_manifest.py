"""Manifest parsing: defaults, per-zone overrides, generated nights, and one clear line per mistake."""

import tomllib

import pytest

from rczone.batch.manifest import parse_manifest, read_manifest
from rczone.errors import DataError


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
    assert room.source == ("file", str((tmp_path / "z.csv").resolve()), None)
    assert room.free == ("Cr", "Rw") and room.n_starts == 2 and room.constants == (("Q", 40.0),)
    assert m.tasks[1].source == ("file", "C", None)  # a built-in data set by name
    gen = [t for t in m.tasks if t.zone == "g-autumn-forced-4"]
    assert [t.method for t in gen] == ["ls", "ml"] and gen[0].source == ("virtual", "autumn", "forced", 4)
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
        ('n_starts = 0\n[[zone]]\nid="a"\ndata="C"', r"n_starts must be an integer from 1 to 1000"),
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
