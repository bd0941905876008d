"""Regenerate the built-in data sets: ``python -m rczone.datasets.generate --out DIR``.

Writes ``A.csv``, ``B.csv`` and ``C.csv`` (see :mod:`rczone.datasets`) with the precision
of :data:`FLOAT_FORMAT`; the shipped files are exactly this command's output.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd

from rczone.virtual.scenarios import SCENARIOS, scenario

#: Printed precision of every column but ``time`` (1e-4 degC, 1e-4 kg/s, 1e-4 W).
FLOAT_FORMAT = "%.4f"


def to_csv_text(df: pd.DataFrame) -> str:
    """The CSV text of a generated night as shipped (``time`` as integer seconds)."""
    out = df.copy()
    out["time"] = out["time"].round().astype(int)
    return out.to_csv(index=False, float_format=FLOAT_FORMAT, lineterminator="\n")


def generate(out: Path, names: tuple[str, ...] = tuple(SCENARIOS)) -> list[Path]:
    """Write the named data sets into folder ``out``; returns the paths."""
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for n in names:
        p = out / f"{n}.csv"
        p.write_text(to_csv_text(scenario(n)), encoding="utf-8")
        paths.append(p)
    return paths


def main(argv: list[str] | None = None) -> None:
    """Command-line entry point."""
    ap = argparse.ArgumentParser(prog="python -m rczone.datasets.generate", description=__doc__)
    ap.add_argument("--out", type=Path, required=True, help="folder to write A.csv, B.csv, C.csv into")
    args = ap.parse_args(argv)
    for p in generate(args.out):
        print(p)


if __name__ == "__main__":
    main()
