"""``dnasim run``: options, the output directory made safe, the run streamed to its
files, the summary; SIGTERM/SIGINT turned into an interrupted run with its rows kept."""

from __future__ import annotations

import os
import signal
import sys
from pathlib import Path

import click

from dnasim.cli.base import (
    CONTEXT_SETTINGS,
    EXIT_SIMULATION,
    InputError,
    SimulationFailed,
    _internal,
    _load,
    _located,
    _need_extra,
    _parse_option_quantity,
    _split_patterns,
    main,
)
from dnasim.core.interrupts import Terminated as _Terminate
from dnasim.core.interrupts import release as _release_signals


def _on_sigterm(signum, frame):
    raise _Terminate()


def _catch_sigterm():
    """Turn SIGTERM into ``_Terminate`` from now on; returns the old handler
    (None when not in the main thread, e.g. inside a test runner thread, or when
    ``dnasim.cli.entry`` already installed its handlers: they raise the same)."""
    from dnasim.core.interrupts import installed

    if installed():
        return None
    try:
        return signal.signal(signal.SIGTERM, _on_sigterm)
    except ValueError:
        return None


def _coolprop_cache(directory: str | None) -> None:
    """Where CoolProp keeps its BICUBIC/TTSE tables (CoolProp's configuration key
    ALTERNATIVE_TABLES_DIRECTORY); ``--coolprop-cache`` or $DNASIM_COOLPROP_CACHE,
    else CoolProp's default $HOME/.CoolProp."""
    directory = directory or os.environ.get("DNASIM_COOLPROP_CACHE") or None
    from dnasim.plant import plantfile

    plantfile.TABULAR_NOTICE = _tabular_notice
    if directory is None:
        return
    path = Path(directory)
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(
            f"option --coolprop-cache: cannot create {path}: {exc.strerror or exc}"
        ) from None
    if not os.access(path, os.W_OK):
        raise InputError(f"option --coolprop-cache: {path} is not writable")
    import CoolProp.CoolProp as CP

    # CoolProp appends its subdirectory to this string as it is: end with a separator
    CP.set_config_string(CP.ALTERNATIVE_TABLES_DIRECTORY, os.path.join(path.resolve(), ""))


def _tabular_notice(medium: str) -> None:
    import CoolProp.CoolProp as CP

    where = CP.get_config_string(CP.ALTERNATIVE_TABLES_DIRECTORY) or str(Path.home() / ".CoolProp")
    click.echo(
        f"dnasim: note: medium {medium!r} uses CoolProp property tables: the first use "
        f"builds them (about 15 MB, 15 s or more) and stores them under {where} "
        "(choose the place with --coolprop-cache DIR or DNASIM_COOLPROP_CACHE)",
        err=True,
    )


def _prepare_output(out: Path) -> None:
    """Create the output directory and remove the previous run's results in it, before
    anything of the new run can fail."""
    from dnasim.core.errors import OutputError
    from dnasim.run.output import clear_results

    try:
        out.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise InputError(f"the output directory {out} exists and is not a directory") from None
    except OSError as exc:
        raise InputError(
            f"cannot create the output directory {out}: {exc.strerror or exc}"
        ) from None
    if not os.access(out, os.W_OK | os.X_OK):
        raise InputError(f"the output directory {out} is not writable")
    try:
        clear_results(out)
    except OutputError as exc:
        raise InputError(str(exc)) from None


_COOLPROP_CACHE_OPTION = click.option(
    "--coolprop-cache",
    default=None,
    metavar="DIR",
    help="Directory for CoolProp's BICUBIC/TTSE property tables "
    "[default: $DNASIM_COOLPROP_CACHE, else ~/.CoolProp].",
)


_ALLOW_IMPORT_OPTION = click.option(
    "--allow-import",
    is_flag=True,
    help="Import the Python modules the plant file's [plant] import names (their code "
    "runs); without it such a plant file is refused.",
)


_UNITS_OPTION = click.option(
    "--units",
    type=click.Choice(["si", "engineering"]),
    default="si",
    show_default=True,
    help="Plot units: SI, or engineering (degC, bar, t/h, kJ/kg, MW).",
)


@main.command(context_settings=CONTEXT_SETTINGS)
@click.argument("plant_file", metavar="PLANT.toml", type=click.Path(dir_okay=False))
@click.option(
    "-o",
    "--output",
    "out_dir",
    default=None,
    metavar="DIR",
    help="Directory for results.csv, events.csv, steps.csv and plots "
    "[default: results/<plant file name>]. The previous run's files there are removed first.",
)
@click.option("--t-end", default=None, metavar="T", help='End time, e.g. 900 or "15 min".')
@click.option("--rtol", type=float, default=None, metavar="R", help="Relative tolerance.")
@click.option(
    "--atol-scaled",
    "atol",
    type=float,
    default=None,
    metavar="A",
    help="Absolute tolerance per unit of each variable's scale.",
)
@click.option("--max-order", type=click.IntRange(1, 5), default=None, help="Maximum BDF order.")
@click.option(
    "--max-steps",
    type=int,
    default=None,
    metavar="N",
    help="Most accepted steps before the run stops [default: [simulation] max_steps, else 500000].",
)
@click.option(
    "--output-interval", default=None, metavar="DT", help='Time between CSV rows, e.g. "1 s".'
)
@click.option(
    "--format",
    "result_format",
    type=click.Choice(["csv", "netcdf", "both"]),
    default="both",
    show_default=True,
    help="Results written while the run goes on: results.csv (text, one column per "
    "variable), results.nc (netCDF-4, units in attributes, vectors as dimensions; "
    "read with dnasim.read_results or xarray), or both.",
)
@click.option(
    "--progress/--no-progress",
    default=None,
    help="Progress line on stderr [default: when stderr is a terminal and not -q].",
)
@click.option("--plot", is_flag=True, help="Write PNG plots (variables; step size and order).")
@click.option(
    "--vars",
    "var_patterns",
    multiple=True,
    metavar="PATTERN",
    help="Variables to plot (implies --plot): names or shell patterns (pipe1.*, *.T_out); "
    "repeat the option or separate with commas. Default: temperatures and controller outputs.",
)
@_UNITS_OPTION
@click.option(
    "--report",
    "html_report",
    is_flag=True,
    help="Write report.html: interactive plots, events, steps, statistics, plant structure.",
)
@_COOLPROP_CACHE_OPTION
@_ALLOW_IMPORT_OPTION
@click.option("-q", "--quiet", is_flag=True, help="No progress bar and no summary.")
def run(
    plant_file,
    out_dir,
    t_end,
    rtol,
    atol,
    max_order,
    max_steps,
    output_interval,
    result_format,
    progress,
    plot,
    var_patterns,
    units,
    html_report,
    coolprop_cache,
    allow_import,
    quiet,
):
    """Simulate PLANT.toml and write results.csv, events.csv, steps.csv (and plots) to DIR.

    results.csv is written while the integration runs and flushed periodically: a
    failure or Ctrl-C leaves a valid CSV up to the time reached.
    """
    old = _catch_sigterm()  # first: a SIGTERM while starting up is reported too
    out = Path(out_dir) if out_dir else Path("results") / Path(plant_file).stem
    if html_report:
        _need_extra("plotly", "report", "option --report")
    try:
        _run(
            plant_file,
            out,
            t_end,
            rtol,
            atol,
            max_order,
            max_steps,
            output_interval,
            plot,
            var_patterns,
            coolprop_cache,
            quiet,
            units=units,
            html_report=html_report,
            allow_import=allow_import,
            result_format=result_format,
            progress=progress,
        )
    except (KeyboardInterrupt, _Terminate) as exc:  # outside the integration itself
        what = "SIGTERM" if isinstance(exc, _Terminate) else "Ctrl-C"
        raise SimulationFailed(
            f"interrupted ({what}) while starting or finishing the run; no results were "
            f"computed beyond what {out / 'results.csv'} holds (if it exists)"
        ) from None
    finally:
        if old is not None:
            signal.signal(signal.SIGTERM, old)


def _run(
    plant_file,
    out,
    t_end,
    rtol,
    atol,
    max_order,
    max_steps,
    output_interval,
    plot,
    var_patterns,
    coolprop_cache,
    quiet,
    units="si",
    html_report=False,
    allow_import=False,
    result_format="csv",
    progress=None,
):

    try:
        _prepare_output(out)
    finally:
        _release_signals()  # a signal held since the start: delivered now
    formats = ("csv", "netcdf") if result_format == "both" else (result_format,)
    if "csv" not in formats and (plot or var_patterns or html_report):
        raise InputError(
            "options --plot/--vars/--report read results.csv: use --format csv or --format both"
        )
    _coolprop_cache(coolprop_cache)
    loaded = _load(plant_file, allow_import)
    _freeze_setup_objects()
    sim = loaded.simulation
    x = _parse_option_quantity(t_end, "s", "--t-end")
    if x is not None:
        if x <= sim.t_start:
            raise InputError(f"option --t-end: must be after the start time {sim.t_start:g} s")
        sim.t_end = x
    from dnasim.plant.spec import setting_problem

    for option, key, value in (
        ("--rtol", "rtol", rtol),
        ("--atol-scaled", "atol_scaled", atol),
        ("--max-order", "max_order", max_order),
        ("--max-steps", "max_steps", max_steps),
    ):
        if value is not None:
            problem = setting_problem(key, value)
            if problem:
                raise InputError(f"option {option}: {problem.replace('max_steps', option)}")
            setattr(sim, key, value)
    dt = _parse_option_quantity(output_interval, "s", "--output-interval")
    if dt is not None:
        sim.output_interval = dt
        sim.t_eval = None  # the option replaces the file's output times
    from dnasim.core.errors import DnasimError, OutputError, PlantError

    try:
        sim.check_output_points()
    except PlantError as exc:
        if sim.t_eval is not None:  # the file's t_eval against --t-end
            src = f"{plant_file} with option --t-end" if x is not None else plant_file
        else:
            src = "options --output-interval/--t-end" if (dt or x) else plant_file
        raise InputError(f"{src}: {exc}") from None
    patterns = _split_patterns(var_patterns)
    plot = plot or bool(patterns)

    from dnasim.run.runner import RunOutcome, run_plant

    show_progress = (not quiet and sys.stderr.isatty()) if progress is None else progress
    try:
        system = None
        if patterns:  # checked against the plant's outputs before anything runs
            from dnasim.compilation.compiler import compile as compile_plant

            system = compile_plant(loaded.plant)
            _check_var_patterns(system, patterns, plant_file)
        outcome: RunOutcome = run_plant(
            loaded,
            out,
            progress=show_progress,
            interrupt_types=(KeyboardInterrupt, _Terminate),
            system=system,
            formats=formats,
        )
    except click.ClickException:
        raise
    except (KeyboardInterrupt, _Terminate):
        raise
    except OutputError as exc:
        raise InputError(str(exc)) from None
    except PlantError as exc:
        from dnasim.plant.plantfile import locate_messages

        text = "\n".join(locate_messages(plant_file, str(exc).split("\n")))
        raise InputError(f"{plant_file}: {text}") from None
    except DnasimError as exc:
        raise InputError(f"{plant_file}: the plant cannot be simulated: {exc}") from None
    except Exception as exc:
        located = _located(exc, plant_file)
        if located is not None:
            raise InputError(located) from None
        raise _internal(exc, EXIT_SIMULATION) from None

    not_written = None  # a plot or report that did not fit: exit 2 after the summary
    if plot and outcome.t_reached is not None and outcome.status != "output-error":
        from dnasim.run.runner import write_plots

        try:
            files = write_plots(outcome, out, patterns, units=units)
        except OutputError as exc:
            not_written, files = exc, []
        except Exception as exc:  # a plot must not hide the result of the run
            click.echo(f"dnasim: warning: plotting failed: {type(exc).__name__}: {exc}", err=True)
            files = []
        if not quiet:
            for f in files:
                click.echo(f"wrote {f}")
    if html_report and outcome.t_reached is not None and outcome.status != "output-error":
        from dnasim.tools.report import write_report

        try:
            f = write_report(outcome, loaded, out, units=units)
        except OutputError as exc:
            not_written = not_written or exc
        except Exception as exc:  # a report must not hide the result of the run
            click.echo(f"dnasim: warning: report failed: {type(exc).__name__}: {exc}", err=True)
        else:
            if not quiet:
                click.echo(f"wrote {f}")
    for w in outcome.warnings:  # the components' warnings (a cavitating pump), even with -q
        click.echo(f"dnasim: warning: {w}", err=True)
    if not quiet or not outcome.success:
        click.echo(outcome.summary())
    if outcome.status == "output-error":
        raise InputError(outcome.failure_message())
    if not outcome.success:
        raise SimulationFailed(outcome.failure_message())
    if not_written is not None:
        raise InputError(
            f"{not_written}; the run {outcome.status} and its results.csv, events.csv and "
            f"steps.csv in {out} are complete. Free disk space (or raise the file size "
            "limit) and run again, or draw the plots from the saved results with "
            f"`dnasim plot {out / 'results.csv'}`"
        )


def _check_var_patterns(system, patterns, plant_file) -> None:
    """``--vars``: raise ``InputError`` (exit 2) naming each pattern that matches none
    of the plant's plotted outputs, with the closest names."""
    import difflib

    from dnasim.run.output import select_variables
    from dnasim.tools.plots import NOT_PLOTTED

    names = [n for n in system.output_names() if n not in NOT_PLOTTED]
    bad = [p for p in patterns if not select_variables(names, [p])]
    if not bad:
        return
    parts = []
    for p in bad:
        stem = p.rstrip("*?[]")
        close = difflib.get_close_matches(p, names, n=4, cutoff=0.6)
        close += [n for n in names if stem and n.startswith(stem) and n not in close][:4]
        hint = f"; did you mean {', '.join(repr(c) for c in close[:4])}?" if close else ""
        parts.append(f"{p!r} matches no output of the plant{hint}")
    components = sorted({n.split(".")[0] for n in names})
    text = "; ".join(parts)
    raise InputError(
        f"{plant_file}: option --vars: {text}{'' if text.endswith('?') else '.'} A pattern is "
        "an output name ('pipe.T_out'), a component ('pipe') or a shell pattern ('pipe.*', "
        "'*.T_out'); the components with outputs are "
        + ", ".join(components[:30])
        + (" ..." if len(components) > 30 else "")
        + ". Nothing was simulated."
    )


def _freeze_setup_objects() -> None:
    """In the ``dnasim`` process (started through ``dnasim.cli.entry``), move the objects of
    the set-up (the imported modules, numba's compiled kernels and its type registries:
    about 10^5 objects) to the garbage collector's permanent generation, so that the
    full collections during the run no longer walk them (0.1 s CPU of a small plant's
    run; ``gc.freeze``). Not done when the command runs inside another program (tests,
    ``CliRunner``): the objects are theirs."""
    from dnasim.core.interrupts import installed

    if installed():
        import gc

        gc.freeze()
