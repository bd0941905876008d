"""``rczone emulate`` as a function: run EnergyPlus, export the trends, write the folder.

:func:`emulate_to_folder` is what the command line calls: the emulator runs the prototype under
its own control (``test="normal"``) or under a forced-response test of some zones
(``test="forced"``, :mod:`rczone.emulators.forced`), and the export of :mod:`rczone.emulators.bms`
is written atomically into the folder.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rczone.emulators.bms import export
from rczone.emulators.energyplus import Emulation, EnergyPlusEmulator
from rczone.errors import ParameterError

#: What ``--test`` may be.
TESTS = ("normal", "forced")


@dataclass(frozen=True, eq=False, repr=False)
class EmulateResult:
    """An emulation and the files written.

    Attributes
    ----------
    run : Emulation
    folder : Path
    files : tuple of str
        Names of the files written into ``folder``.
    test : str
    """

    run: Emulation
    folder: Path
    files: tuple[str, ...]
    test: str

    def summary(self) -> str:
        """What the command prints."""
        return (
            self.run.summary()
            + f"{self.test} test; wrote {len(self.files)} files to {os.fspath(self.folder)}:"
            + f" {', '.join(self.files)}\n"
        )

    def to_dict(self) -> dict:
        """The run and the files, JSON-ready."""
        return {**self.run.to_dict(), "test": self.test, "files": list(self.files)}

    def to_frame(self):
        """The run's time-step table (true values)."""
        return self.run.to_frame()


def emulate_to_folder(
    building: str,
    weather: str,
    out: str | os.PathLike,
    *,
    start: str = "01-15",
    days: int = 2,
    step_minutes: int = 5,
    seed: int = 0,
    test: str = "normal",
    zones: str | None = None,
    progress: Any = None,
) -> EmulateResult:
    """Run a prototype and write ``trend.csv``, a column map per conditioned zone and ``building.toml``.

    Parameters
    ----------
    building, weather : str
        As :class:`~rczone.emulators.energyplus.EnergyPlusEmulator`.
    out : path
        Folder for the files (created).
    start, days, step_minutes
        As :class:`~rczone.emulators.energyplus.EnergyPlusEmulator`.
    seed : int
        Seed of the sensor noise.
    test : {"normal", "forced"}
    zones : str, optional
        The zones a forced test drives, comma-separated (default: the first conditioned zone).
    progress : object, optional
        Told ``progress.advance(days_done, days)`` after each simulated day; None: nothing.

    Returns
    -------
    EmulateResult
    """
    from rczone.files.atomic import ensure_folder, write_text_in

    if test not in TESTS:
        from rczone.errors import did_you_mean

        raise ParameterError(f"--test {test!r}: {did_you_mean(test, TESTS)}")
    em = EnergyPlusEmulator(building, weather, start=start, days=days, step_minutes=step_minutes)
    folder = ensure_folder(out)  # a file in the way is one line before EnergyPlus runs, not after
    if test == "forced":
        from rczone.emulators.forced import forced_run

        run = forced_run(em, zones, progress)
    else:
        if zones:
            raise ParameterError("--zones is for --test forced (the zones the test drives)")
        run = em.run(progress=progress)
    files = export(run, seed=seed, test=test).files
    for name, text in files.items():
        write_text_in(folder, name, text)
    return EmulateResult(run, Path(folder), tuple(files), test)
