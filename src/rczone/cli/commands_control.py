"""``rczone control-test``: run a controller on a zone of the virtual building, of an EnergyPlus
prototype (``--emulator energyplus``) or of a heated house (``--emulator house``), and score it."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rczone.cli.common import MODEL_HELP, QuietOption, esc, model, out_console, write_json
from rczone.cli.main import app
from rczone.cli.progress import Steps, reporter
from rczone.errors import ParameterError


@app.command("control-test")
def control_test(
    model_spec: Annotated[
        str | None,
        typer.Option(
            "--model",
            help=MODEL_HELP + " Default second-order. energyplus with --zones ZONE,ZONE: one joint model of"
            " those zones (rczone models generate --from DIR/building.toml --floor N, fitted): the floor MPC.",
        ),
    ] = None,
    scenario: Annotated[str, typer.Option("--scenario", help="summer or winter.")] = "summer",
    days: Annotated[float, typer.Option("--days", help="Days to run (from 6 pm).")] = 1.0,
    seed: Annotated[int, typer.Option("--seed", help="Weather, settings and noise.")] = 0,
    controller: Annotated[
        str,
        typer.Option(
            "--controller",
            help="mpc, thermostat (commissioned), naive (schedule set points), oracle, or a registered"
            " or plug-in controller (entry-point group rczone.controllers).",
        ),
    ] = "mpc",
    no_disturbance: Annotated[
        bool, typer.Option("--no-disturbance", help="The MPC's observer estimates no unmeasured heat input.")
    ] = False,
    price: Annotated[
        str,
        typer.Option(
            "--price",
            help="flat; tou: 3x price from noon to 6 pm; dr: a demand-response event, 10x price from 2 pm"
            " to 4 pm announced at 11 am (the MPC minimizes cost).",
        ),
    ] = "flat",
    band: Annotated[
        str,
        typer.Option(
            "--band",
            help="normal: the thermostat's comfort band; tight: its occupied band narrowed to 0.8 K.",
        ),
    ] = "normal",
    forecast: Annotated[
        str | None,
        typer.Option(
            "--forecast",
            help="virtual: measured (default; diurnal outdoor curve shifted by the last error), perfect"
            " (the run's true weather and prices), biased (measured + 2 K); energyplus: BOPTEST's"
            " forecast uncertainty none (default), low, medium, high.",
        ),
    ] = None,
    emulator: Annotated[
        str,
        typer.Option(
            "--emulator",
            help="virtual (the built-in building), energyplus, house (a room with an electric heater), or a"
            " registered or plug-in emulator (entry-point group rczone.emulators; given --days, --seed and"
            " --price).",
        ),
    ] = "virtual",
    building: Annotated[
        str | None,
        typer.Option("--building", help="energyplus: a prototype (office_small, office_medium...)."),
    ] = None,
    weather: Annotated[
        str, typer.Option("--weather", help="energyplus: a TMY3 weather file (rczone emulate --list).")
    ] = "usa_il_chicago",
    start: Annotated[str, typer.Option("--start", help="energyplus: first day, MM-DD.")] = "01-17",
    zone: Annotated[
        str | None, typer.Option("--zone", help="energyplus: the zone the controller runs.")
    ] = None,
    zones: Annotated[
        str | None,
        typer.Option(
            "--zones",
            help="energyplus: several zones, each with its model, ZONE=MODEL,ZONE=MODEL (mpc: one"
            " supervisory MPC per zone, neighbours as measured inputs); ZONE,ZONE for baseline, or"
            " ZONE,ZONE with --model of their joint floor model (mpc: one floor MPC).",
        ),
    ] = None,
    step: Annotated[int, typer.Option("--step", help="energyplus: the plant's step, minutes.")] = 15,
    heat_limit: Annotated[
        float | None,
        typer.Option(
            "--heat-limit",
            help="house: the heater's largest power, W (default 3000); the MPC and the thermostat are"
            " both held to it.",
        ),
    ] = None,
    margin: Annotated[
        float | None,
        typer.Option("--margin", help="energyplus mpc: how far inside the comfort band it aims, K (0.1)."),
    ] = None,
    noise_floor: Annotated[
        float,
        typer.Option(
            "--noise-floor",
            help="Lowest sensor noise (K) the prediction score's filter assumes; default the 0.1 F resolution.",
        ),
    ] = 0.1 * 5.0 / 9.0,
    compare: Annotated[
        str | None,
        typer.Option(
            "--compare",
            help="Compare controllers (and models) on the same seeds: comma-separated CONTROLLER[:MODEL]"
            " (e.g. 'thermostat,mpc,mpc:first-order,oracle'); the first is the reference; MPCs without"
            " :MODEL use --model.",
        ),
    ] = None,
    seeds: Annotated[
        int,
        typer.Option(
            "--seeds", help="With --compare or --study: seeds --seed, --seed + 1, ... (paired runs)."
        ),
    ] = 1,
    study: Annotated[
        str | None,
        typer.Option(
            "--study",
            help="paper: the paper's Q1 (13-, 2-, 1-state models) and Q2 (fitted on forced vs closed-loop"
            " data) under the MPC, with the commissioned thermostat, paired over --seeds in one table.",
        ),
    ] = None,
    json_out: Annotated[
        Path | None, typer.Option("--json", help="Write the scores as JSON ('-': stdout).")
    ] = None,
    report_dir: Annotated[
        Path | None, typer.Option("--report", help="Folder for report.html and figures.")
    ] = None,
    quiet: QuietOption = False,
) -> None:
    """Closed-loop test: comfort (K h), energy (kWh), cost, peak, prediction RMSE, solve time."""
    from rczone.control.closedloop import closed_loop_test
    from rczone.control.virtualplant import VirtualPlant
    from rczone.emulators.registry import EMULATORS

    EMULATORS.factory(emulator)  # an unknown name (or a plug-in that fails to load) is one line
    _refuse_unread(
        emulator,
        {"--scenario": scenario, "--band": band, "--building": building, "--weather": weather}
        | {"--start": start, "--zone": zone, "--zones": zones, "--step": step, "--margin": margin},
    )
    if heat_limit is not None and emulator in ("virtual", "energyplus"):
        raise ParameterError(
            f"--heat-limit is for a heated zone (--emulator house); the {emulator} building has VAV boxes"
        )
    zm = model(model_spec or "second-order")
    out = out_console(json_out)
    if emulator == "energyplus":
        from rczone.emulators.control import energyplus_test

        if compare is not None or study is not None or report_dir is not None:
            raise ParameterError(
                "--compare, --study and --report are for the virtual building; run each controller alone"
            )
        options = dict(weather=weather, start=start, step_minutes=step, seed=seed, price=price)
        names, models = _zones_and_models(zone, zones, zm, joint=model_spec is not None)
        plant = _energyplus_plant(building, names, days, forecast or "none", options)
        res = energyplus_test(plant, controller, model=models, margin_K=margin, noise_floor=noise_floor)
        out.print(esc(res.summary()))
        write_json(json_out, res.to_dict())
        return
    if emulator != "virtual":  # a registered or plug-in emulator, with the options every plant has
        from rczone.emulators.registry import make_plant

        if compare is not None or study is not None or report_dir is not None or forecast is not None:
            raise ParameterError(
                "--compare, --study, --report and --forecast are for the virtual building and energyplus;"
                f" on {emulator!r} run each controller alone"
            )
        limit = {} if heat_limit is None else {"heat_limit": heat_limit}
        plant = make_plant(emulator, days=days, seed=seed, price=price, **limit)
        res = closed_loop_test(
            plant, controller, model=zm, disturbance=not no_disturbance, noise_floor=noise_floor
        )
        out.print(esc(res.summary()))
        write_json(json_out, res.to_dict())
        return
    forecast = forecast or "measured"
    if compare is not None or study is not None:
        from rczone.control.comparison import Scenario, compare_entries
        from rczone.control.comparison import compare as compare_runs
        from rczone.control.study import study_entries

        if seeds < 1:
            raise ParameterError(f"--seeds must be an integer >= 1, got {seeds}")
        if compare is not None and study is not None:
            raise ParameterError("give --compare or --study, not both")
        test = Scenario(scenario, days=days, price=price, comfort_band=band, forecast=forecast)
        if study is not None:
            entries = study_entries(study)
        else:
            entries = compare_entries(compare, zm, model, disturbance=not no_disturbance)
        with reporter(quiet=quiet) as report:
            runs = Steps(
                report, len(entries) * seeds, "closed loop: {name} (run {i} of {n}), simulated hours"
            )
            cmp = compare_runs(entries, list(range(seed, seed + seeds)), scenario=test, progress=runs)
        out.print(esc(cmp.summary()))
        write_json(json_out, cmp.to_dict())
        if report_dir:
            from rczone.control.comparison import comparison_report

            path = comparison_report(cmp, report_dir)
            out.print(f"report written to [bold]{esc(path)}[/]")
        return
    plant = VirtualPlant(scenario, days=days, seed=seed, price=price, comfort_band=band, forecast=forecast)
    with reporter(quiet=quiet) as report:
        report(f"closed loop: {controller} on the {scenario} scenario, simulated hours")
        res = closed_loop_test(
            plant,
            controller,
            model=zm,
            disturbance=not no_disturbance,
            noise_floor=noise_floor,
            progress=report,
        )
    out.print(esc(res.summary()))
    write_json(json_out, res.to_dict())
    if report_dir:
        from rczone.report.control import closed_loop_report

        closed_loop_report(res).write(report_dir)
        out.print(f"report written to [bold]{esc(report_dir / 'report.html')}[/]")


#: Options one emulator reads, with their defaults: given another value elsewhere, they are refused
#: rather than silently ignored.
_READ_BY = {
    "virtual": {"--scenario": "summer", "--band": "normal"},
    "energyplus": {
        "--building": None,
        "--weather": "usa_il_chicago",
        "--start": "01-17",
        "--zone": None,
        "--zones": None,
        "--step": 15,
        "--margin": None,
    },
}


def _refuse_unread(emulator: str, given: dict[str, object]) -> None:
    """One line for an option the chosen emulator would ignore (set away from its default)."""
    for owner, options in _READ_BY.items():
        if owner != emulator:
            for name, default in options.items():
                if given[name] != default:
                    raise ParameterError(
                        f"{name} is read by --emulator {owner} only; the {emulator} emulator would ignore it"
                    )


def _zones_and_models(zone: str | None, zones: str | None, zm, *, joint: bool = False):
    """The controlled zones and their models: ``--zone`` with ``--model``, ``--zones ZONE=MODEL,...``, or
    ``--zones ZONE,ZONE --model floor.json`` (one joint model of them all)."""
    if zones is None:
        return ([zone] if zone is not None else []), zm
    if zone is not None:
        raise ParameterError("give --zone or --zones, not both")
    if joint and "=" in zones:
        raise ParameterError(
            "give each zone its model (--zones ZONE=MODEL,...) or one joint model (--zones ZONE,ZONE --model), not both"
        )
    names, models = [], {}
    for item in zones.split(","):
        name, sep, spec = (part.strip() for part in item.partition("="))
        if not name or (sep and not spec):
            raise ParameterError(f"--zones takes ZONE=MODEL,ZONE=MODEL (or ZONE,ZONE); got {item.strip()!r}")
        if name in names:
            raise ParameterError(f"--zones names {name!r} twice")
        names.append(name)
        if spec:
            models[name] = model(spec)
    if joint:
        return names, zm  # a joint model of the zones (the floor MPC checks it names them)
    from rczone.emulators.control import models_by_zone

    return names, (models_by_zone(models, names) if models else None)  # a model for every zone


def _energyplus_plant(building: str | None, zones: list[str], days: float, forecast: str, options: dict):
    """The EnergyPlus plant of ``--emulator energyplus`` (its own checks say what is wrong)."""
    from rczone.emulators.plant import EnergyPlusPlant

    if building is None or not zones:
        raise ParameterError(
            "--emulator energyplus needs --building and --zone (or --zones) (rczone emulate --list)"
        )
    if days != int(days):
        raise ParameterError(f"--days must be whole days on EnergyPlus, got {days:g}")
    return EnergyPlusPlant(building, zones=zones, days=int(days), forecast=forecast, **options)
