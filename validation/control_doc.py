"""Regenerate the measured tables of ``docs/control.md``: paired comparisons at equal limits, over seeds.

Usage::

    python validation/control_doc.py [--seeds 31,32,33,34] [--oracle] [--paper-seasons summer,winter] [--days 1] [--out validation/control_doc.md]
                                     [--page docs/control.md] [--only baselines|paper|paste]

Every table is one :func:`rczone.control.comparison.compare`: every entry on the same seeds (seeds
no test names), each run held to the plant's limits (the occupied ventilation minimum, the flow
and discharge limits; :func:`~rczone.control.closedloop.check_comparable` refuses a pair that
differs), with the commissioned thermostat (the fair baseline) as the reference unless a row says
otherwise. Tables:

* ``baselines-<scenario>``: ``thermostat`` (reference), ``naive``, ``mpc`` (the paper's 2-state
  model at its construction values) and, with ``--oracle``, ``oracle``, for summer and winter at a flat price,
  summer under the time-of-use price (``tou``) and under a demand-response event (``dr``): what
  the MPC gains and where (comfort, energy, cost, peak flow);
* ``paper-<season>``: the paper's Q1 and Q2 in closed loop (:mod:`rczone.control.study`).

The tables are written to ``--out`` (one block per table between ``<!-- table:NAME -->`` and
``<!-- /table:NAME -->``) and pasted into the same markers of ``--page``;
``tests/validation/test_control_doc.py`` checks that the page carries the output file's tables
and that no test names these seeds. The prose around them is not touched: read it again after a
change of the numbers. The defaults make 96 one-day runs and two fits: some 20 minutes of CPU.
"""

from __future__ import annotations

import argparse
import re
import time
from pathlib import Path

from rczone.control.comparison import Entry, Scenario, compare
from rczone.control.study import paper_entries
from rczone.files.atomic import write_text_atomic
from rczone.models import load_model

HERE = Path(__file__).resolve().parent
OUT = HERE / "control_doc.md"
PAGE = HERE.parent / "docs" / "control.md"
#: Seeds no test names (``tests/validation/test_control_doc.py`` checks).
SEEDS = (31, 32, 33, 34)
#: name -> (season, price)
BASELINES = {
    "summer": ("summer", "flat"),
    "winter": ("winter", "flat"),
    "summer-tou": ("summer", "tou"),
    "summer-dr": ("summer", "dr"),
}


def block(name: str, text: str) -> str:
    return f"<!-- table:{name} -->\n{text}\n<!-- /table:{name} -->"


def blocks(text: str) -> dict[str, str]:
    """The tables of a page or an output file, by name."""
    found = re.findall(r"<!-- table:(\S+) -->\n(.*?)<!-- /table:\1 -->", text, flags=re.S)
    return {name: body.removesuffix("\n") for name, body in found}


def baseline_tables(seeds, days: float, oracle: bool, save) -> dict[str, str]:
    entries = [
        Entry("thermostat (commissioned)", "thermostat"),
        Entry("naive thermostat", "naive"),
        Entry("MPC, 2-state", "mpc", load_model("second-order-paper")),
    ] + ([Entry("oracle", "oracle")] if oracle else [])
    out = {}
    for name, (season, price) in BASELINES.items():
        t0 = time.process_time()
        cmp = compare(entries, seeds, scenario=Scenario(season, days=days, price=price))
        out[f"baselines-{name}"] = cmp.markdown()
        save(out)
        print(f"{name}: {time.process_time() - t0:.0f} s CPU\n{cmp.summary()}", flush=True)
    return out


def paper_tables(seeds, days: float, seasons, save) -> dict[str, str]:
    entries = paper_entries()
    out = {}
    for season in seasons:
        t0 = time.process_time()
        cmp = compare(entries, seeds, scenario=Scenario(season, days=days))
        out[f"paper-{season}"] = cmp.markdown()
        save(out)
        print(f"paper {season}: {time.process_time() - t0:.0f} s CPU\n{cmp.summary()}", flush=True)
    return out


def paste(page: str, tables: dict[str, str]) -> str:
    """``page`` with every table block replaced by the new one (blocks it lacks are left out)."""
    for name, text in tables.items():
        page = re.sub(
            rf"<!-- table:{re.escape(name)} -->\n.*?<!-- /table:{re.escape(name)} -->",
            lambda _m, n=name, t=text: block(n, t),
            page,
            flags=re.S,
        )
    return page


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", default=",".join(map(str, SEEDS)))
    ap.add_argument("--days", type=float, default=1.0)
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--page", type=Path, default=PAGE)
    ap.add_argument("--paper-seasons", default="summer,winter")
    ap.add_argument("--oracle", action="store_true", help="add the oracle to the baseline tables")
    ap.add_argument(
        "--only", choices=("baselines", "paper", "paste"), help="paste: no runs, the tables of --out"
    )
    a = ap.parse_args(argv)
    seeds = [int(s) for s in a.seeds.split(",")]
    tables = blocks(a.out.read_text()) if a.out.exists() else {}
    if a.only == "paste":
        write_text_atomic(a.page, paste(a.page.read_text(), tables))
        return 0

    def save(new: dict[str, str]) -> None:
        tables.update(new)
        write_text_atomic(a.out, "\n\n".join(block(k, v) for k, v in tables.items()) + "\n")

    if a.only in (None, "baselines"):
        baseline_tables(seeds, a.days, a.oracle, save)
    if a.only in (None, "paper"):
        paper_tables(seeds, a.days, tuple(a.paper_seasons.split(",")), save)
    write_text_atomic(a.page, paste(a.page.read_text(), tables))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
