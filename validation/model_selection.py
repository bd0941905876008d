"""Forward model selection on the Bacher & Madsen PRBS experiment (real data, kept outside the project).

Usage::

    python validation/model_selection.py [--shared ../shared] [--out validation-output] [--classic]

Reads ``data/bacher_madsen_prbs/inputPRBS1.csv`` from the shared folder (its licence does not
allow shipping it; nothing is copied into the project) through the column map
``validation/maps/bacher_madsen.toml`` (``Ta`` is the outdoor temperature ``To``, kW to W) and runs

    rczone select DATA --columns validation/maps/bacher_madsen.toml --forward --json ... --report ...

on it: the whole Bacher & Madsen family (``Tm``, ``Te``, ``Th``, the sensor node ``Tsn``, the
solar splits ``Ae`` and ``As``, ``Ria``) with a heater and solar gains, grown from ``Ti`` one part
at a time by likelihood-ratio tests, and prints its path beside the one the paper reports
(``--classic``: through the five candidates of :data:`CLASSIC` only, passed as ``--model``). Prints 'skipped: data not found' and exits 0 when the data are absent.
Writes ``<out>/model_selection.json``, ``<out>/model_selection/report.html`` (``--classic``:
``model_selection_classic``) and prints the tables
as Markdown (the form in docs/validation.md), each candidate with the verdict rczone gives its fit.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from rczone.cli.main import main as rczone

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from verdicts import verdict_cell  # noqa: E402

DEFAULT_SHARED = HERE.parent.parent / "shared"
DATA = Path("data") / "bacher_madsen_prbs" / "inputPRBS1.csv"
COLUMN_MAP = HERE / "maps" / "bacher_madsen.toml"


#: What Bacher & Madsen (2011, section 5) report for these data: the forward path starts
#: Ti -> TiTh -> TiTeTh and ends at the selected TiTmTeThAeRia (their log-likelihoods are not
#: available here; see the data's PROVENANCE.md).
PUBLISHED = {"start": ("Ti", "TiTh", "TiTeTh"), "selected": "TiTmTeThAeRia"}

#: ``--classic``: the five candidates of ``rczone select`` by a criterion (the family before issue
#: 22), each with the heater and solar gains into the interior.
CLASSIC = ("Ti", "TiTe", "TiTh", "TiTeTh", "TiTm")


def base(name: str) -> str:
    """The family base of a candidate name (``TiTeTh+heater+solar`` -> ``TiTeTh``)."""
    return name.partition("+")[0]


def comparison(res: dict) -> str:
    """The forward path beside the published one, as a Markdown table."""
    path = [base(n) for n in res["forward"]["path"]]
    return "\n".join(
        [
            "| | path | selected |",
            "|---|---|---|",
            f"| rczone | {' → '.join(path)} | {path[-1]} |",
            f"| Bacher & Madsen (2011) | {' → '.join(PUBLISHED['start'])} → … | {PUBLISHED['selected']} |",
        ]
    )


def markdown(res: dict) -> str:
    """The candidates, the forward steps and the comparison with the paper as Markdown tables."""
    lines = [
        "| model | log L | k | AIC | BIC | Ljung-Box p (innovations) | white | verdict |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, m in res["models"].items():
        p = m["innovations"]["ljung_box_p"]
        mark = " **(selected)**" if name == res["selected"] else ""
        lines.append(
            f"| {name}{mark} | {m['loglik']:.1f} | {m['n_params']} | {m['aic']:.1f} | {m['bic']:.1f} |"
            f" {p:.2g} | {'yes' if m['innovations']['white'] else 'no'} | {verdict_cell(m['verdict'])} |"
        )
    lines += [
        "",
        "| step | from | extensions fitted | best | LR | df | p | decision |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for k, s in enumerate(res["forward"]["steps"], 1):
        lines.append(
            f"| {k} | {s['from']} | {', '.join(s['tried'])} | {s['best']} | {s['statistic']:.1f} | {s['df']} |"
            f" {s['p_value']:.2g} | {'accepted' if s['accepted'] else 'stop'} |"
        )
    lines += ["", comparison(res)]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", type=Path, default=DEFAULT_SHARED)
    ap.add_argument("--out", type=Path, default=Path("validation-output"))
    ap.add_argument(
        "--classic",
        action="store_true",
        help=f"grow through the five classic candidates only ({', '.join(CLASSIC)}), not the whole family",
    )
    args = ap.parse_args(argv)
    if not (args.shared / DATA).is_file():
        print(f"skipped: data not found under {args.shared / DATA.parent}")
        return 0
    stem = "model_selection_classic" if args.classic else "model_selection"
    out_json = args.out / f"{stem}.json"
    models = [a for b in CLASSIC for a in ("--model", f"{b}+heater+solar")] if args.classic else []
    rc = rczone(
        [
            "select",
            str(args.shared / DATA),
            "--columns",
            str(COLUMN_MAP),
            *models,
            "--forward",
            "--json",
            str(out_json),
            "--report",
            str(args.out / stem),
        ]
    )
    if rc not in (0, 3):
        return rc
    print(markdown(json.loads(out_json.read_text())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
