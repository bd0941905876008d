"""The manifest's ``sampler`` and ``options`` tables: each method's own options, search keys for the rest."""

import tomllib

import pytest

from rczone.batch.manifest import parse_manifest
from rczone.errors import DataError
from rczone.estimation.methods.map import MapOptions
from rczone.estimation.methods.mcmc import McmcOptions
from rczone.estimation.settings import FitSettings


def parse(text, tmp_path):
    return parse_manifest(tomllib.loads(text), tmp_path / "m.toml")


def test_sampler_goes_to_the_sampling_method_and_the_search_keys_to_the_others(tmp_path):
    m = parse(
        """
methods = ["ml", "mcmc"]
optimizer = "lbfgs"
n_starts = 2
sampler = { draws = 300, chains = 2 }

[[zone]]
id = "a"
data = "C"

[[zone]]
id = "b"
data = "C"
sampler = { tune = 50 }
""",
        tmp_path,
    )
    by_key = {t.key: t.settings for t in m.tasks}
    common = {"checks": False, "profiles": False}
    assert by_key["a::ml"] == FitSettings(method="ml", optimizer="lbfgs", n_starts=2, **common)
    assert by_key["a::mcmc"] == FitSettings(
        method="mcmc", options=McmcOptions(draws=300, tune=1000, chains=2), **common
    )
    # a zone's table replaces the top-level one; the keys it leaves out take the defaults
    assert by_key["b::mcmc"].options == McmcOptions(draws=1000, tune=50, chains=4)
    # the sampler's settings are part of what a stored result is reused for
    fingerprints = {t.key: t.fingerprint for t in m.tasks}
    again = parse(
        'methods = ["mcmc"]\nsampler = { draws = 301, chains = 2 }\n[[zone]]\nid = "a"\ndata = "C"', tmp_path
    )
    assert again.tasks[0].key == "a::mcmc" and again.tasks[0].fingerprint != fingerprints["a::mcmc"]


def test_without_a_sampler_table_a_sampling_method_takes_the_defaults_of_fit(tmp_path):
    m = parse('methods = ["mcmc"]\n[[zone]]\nid = "a"\ndata = "C"', tmp_path)
    assert m.tasks[0].settings.options == McmcOptions() == FitSettings(method="mcmc").options


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("sampler = 5", r"sampler must be a table like \{ draws = 1000, tune = 1000, chains = 4 \}, got 5"),
        (
            "sampler = { draw = 10 }",
            r"m.toml.sampler: method 'mcmc' has no option 'draw'; did you mean 'draws'",
        ),
        ("sampler = { draws = 5 }", r"option draws must be an integer from 10 to 1,000,000, got 5"),
        ("sampler = { draws = 100.0 }", r"option draws must be an integer .* got 100.0"),
        ("sampler = { chains = true }", r"option chains must be an integer from 1 to 64, got True"),
        ("sampler = { tune = 100000000000 }", r"option tune must be an integer from 10 to 1,000,000"),
    ],
)
def test_bad_sampler_tables_are_one_line(tmp_path, text, match):
    with pytest.raises(DataError, match=match) as info:
        parse(text + '\nmethods = ["mcmc"]\n[[zone]]\nid = "a"\ndata = "C"', tmp_path)
    assert "\n" not in str(info.value) and str(info.value).startswith("manifest ")


def test_a_bad_sampler_table_of_a_zone_names_the_zone(tmp_path):
    with pytest.raises(DataError, match=r"zone 1 \(a\)\.sampler: option chains must be an integer"):
        parse('methods = ["mcmc"]\n[[zone]]\nid = "a"\ndata = "C"\nsampler = { chains = 0 }', tmp_path)


def test_an_options_table_goes_to_the_method_it_names(tmp_path):
    m = parse(
        'methods = ["ml", "map"]\noptions = { map = { prior_spread = 0.5 } }\n[[zone]]\nid = "a"\ndata = "C"',
        tmp_path,
    )
    by_key = {t.key: t.settings for t in m.tasks}
    assert by_key["a::map"].options == MapOptions(prior_spread=0.5)
    assert by_key["a::ml"].options.to_dict() == {}


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (
            "options = { map = { prior = 0.5 } }",
            r"method 'map' has no option 'prior'; did you mean 'prior_spread'",
        ),
        ("options = { mapp = { prior_spread = 0.5 } }", r"unknown method 'mapp'; did you mean 'map'"),
        ("options = { map = 3 }", r"options must be a table of tables by method"),
        ("options = { map = { prior_spread = -1.0 } }", r"option prior_spread must be a finite number > 0"),
    ],
)
def test_bad_options_tables_are_one_line(tmp_path, text, match):
    with pytest.raises(DataError, match=match) as info:
        parse(text + '\nmethods = ["map"]\n[[zone]]\nid = "a"\ndata = "C"', tmp_path)
    assert "\n" not in str(info.value) and str(info.value).startswith("manifest ")
