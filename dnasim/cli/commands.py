"""The ``dnasim`` command: run, steady, sweep, check, components, plot, linearize, fmu.

Exit codes: 0 success; 1 the simulation failed or was interrupted (results up to
that time are on disk); 2 bad input (plant file, options, paths).

Heavy modules (numpy, the solver, CoolProp, matplotlib) are imported inside the
commands, so ``dnasim --help`` starts fast.
"""

from __future__ import annotations

import signal
import sys

if (
    __name__ == "__main__"
):  # python -m dnasim.cli.commands: the signal handlers before anything else
    from dnasim.core.interrupts import install

    install()

import os
import re
import traceback
from pathlib import Path

import click

from dnasim.core.interrupts import Terminated as _Terminate
from dnasim.core.interrupts import release as _release_signals

EXIT_OK = 0
EXIT_SIMULATION = 1
EXIT_INPUT = 2

CONTEXT_SETTINGS = {"help_option_names": ["-h", "--help"], "max_content_width": 100}


class InputError(click.ClickException):
    """Bad input: printed as one message without a traceback, exit code 2."""

    exit_code = EXIT_INPUT

    def show(self, file=None):
        click.echo(f"dnasim: error: {self.format_message()}", err=True)


class SimulationFailed(click.ClickException):
    exit_code = EXIT_SIMULATION

    def show(self, file=None):
        click.echo(f"dnasim: {self.format_message()}", err=True)


def _debug() -> bool:
    return bool(os.environ.get("DNASIM_DEBUG"))


def _internal(exc: BaseException, exit_code: int) -> click.ClickException:
    """An unexpected exception: a one-line message (traceback with DNASIM_DEBUG=1)."""
    if _debug():
        traceback.print_exc()
    err = SimulationFailed(
        f"internal error: {type(exc).__name__}: {exc} "
        "(this is a bug in dnasim; set DNASIM_DEBUG=1 for the traceback)"
    )
    err.exit_code = exit_code
    return err


def _load(plant_file: str, allow_import: bool = False):
    from dnasim.core.errors import PlantError
    from dnasim.plant.plantfile import load

    try:
        return load(plant_file, allow_import=allow_import)
    except PlantError as exc:
        raise InputError(str(exc)) from None
    except click.ClickException:
        raise
    except Exception as exc:  # a bug, but never a traceback for the user
        located = _located(exc, plant_file)
        if located is not None:
            raise InputError(located) from None
        raise _internal(exc, EXIT_INPUT) from None


def _parse_option_quantity(value, unit: str, option: str) -> float | None:
    if value is None:
        return None
    from dnasim.core.units import UnitError, to_si

    try:
        v = float(value)
    except ValueError:
        v = value
    try:
        x = to_si(v, unit)
    except UnitError as exc:
        raise InputError(f"option {option}: {exc}") from None
    if not x > 0:
        raise InputError(f"option {option}: must be positive (got {value})")
    return x


def _need_extra(module: str, extra: str, what: str) -> None:
    """Refuse ``what`` before any work when the optional ``module`` is not installed."""
    import importlib

    try:
        importlib.import_module(module)
    except ImportError:
        raise InputError(
            f"{what} needs {module}, an optional dependency: pip install 'dnasim[{extra}]'"
        ) from None


def _split_patterns(values) -> list[str]:
    out = []
    for v in values or ():
        for part in v.replace(",", " ").split():
            if part:
                out.append(part)
    return out


@click.group(context_settings=CONTEXT_SETTINGS)
@click.version_option(package_name="dnasim", prog_name="dnasim")
@click.pass_context
def main(ctx):
    """dnasim: dynamic simulation of energy systems (plants of pipes, valves,
    attemperators and controllers), solved as index-1 DAEs by a Nordsieck BDF.

    \b
    Plant files are TOML; see `dnasim components` for the component library
    and docs/plant_files.md for the schema.
    \b
    Exit codes: 0 success, 1 simulation failed or interrupted (results up to
    that time are written), 2 bad input.
    """
    # A signal held since the program started (dnasim.cli.entry) is delivered now; `run`
    # delivers it only after it has cleared its output directory.
    if ctx.invoked_subcommand != "run":
        _release_signals()
    from dnasim.plant import migrations as plant_migrations  # old plant-file keys: one notice each

    plant_migrations.NOTICE = lambda msg: click.echo(f"dnasim: notice: {msg}", err=True)


# --------------------------------------------------------------------------- run


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


def _located(exc: BaseException, plant_file: str) -> str | None:
    """An environment or input problem that is not a bug, as a one-line message."""
    if isinstance(exc, MemoryError):
        return (
            f"{plant_file}: out of memory while building or simulating the plant; reduce "
            "n_volumes/n_sections, the number of components or the output points"
        )
    if isinstance(exc, RecursionError):
        return f"{plant_file}: the plant is nested too deeply to be read"
    return None


# --------------------------------------------------------------------------- check


@main.command(context_settings=CONTEXT_SETTINGS)
@click.argument("plant_file", metavar="PLANT.toml", type=click.Path(dir_okay=False))
@_COOLPROP_CACHE_OPTION
@_ALLOW_IMPORT_OPTION
def check(plant_file, coolprop_cache, allow_import):
    """Validate PLANT.toml and analyse its structure (equations, unknowns, states,
    matching) without simulating. Exits 2 on any problem."""
    old = _catch_sigterm()
    try:
        _check(plant_file, coolprop_cache, allow_import)
    except (KeyboardInterrupt, _Terminate) as exc:
        what = "SIGTERM" if isinstance(exc, _Terminate) else "Ctrl-C"
        raise SimulationFailed(f"{plant_file}: check interrupted ({what})") from None
    finally:
        if old is not None:
            signal.signal(signal.SIGTERM, old)


def _check(plant_file, coolprop_cache, allow_import=False):
    from dnasim.core.errors import DnasimError, PlantError

    _coolprop_cache(coolprop_cache)
    loaded = _load(plant_file, allow_import)
    try:
        from dnasim.compilation.compiler import check

        # structure analysis on the System, built once (media, sparsity, events)
        report, _system = check(loaded.plant)
    except PlantError as exc:
        raise InputError(f"{plant_file}: {exc}") from None
    except DnasimError as exc:
        raise InputError(f"{plant_file}: structural analysis failed: {exc}") from None
    except Exception as exc:
        located = _located(exc, plant_file)
        if located is not None:
            raise InputError(located) from None
        raise _internal(exc, EXIT_INPUT) from None
    from dnasim.plant.plantfile import locate_messages, notices
    from dnasim.run.runner import describe_report

    try:
        text = Path(plant_file).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        text = None
    for note in notices(loaded.spec, text):
        click.echo(f"dnasim: note: {note}", err=True)
    report.errors = locate_messages(plant_file, report.errors)
    text, ok = describe_report(report)
    click.echo(
        f"{plant_file}: plant '{loaded.spec.name}', {len(loaded.spec.components)} components"
    )
    click.echo(text)
    if not ok:
        raise InputError(f"{plant_file}: the structural analysis found problems (see above)")
    click.echo("ok")


# --------------------------------------------------------------------------- steady


@main.command(context_settings=CONTEXT_SETTINGS)
@click.argument("plant_file", metavar="PLANT.toml", type=click.Path(dir_okay=False))
@click.option(
    "-o",
    "--output",
    "out_dir",
    default=None,
    metavar="DIR",
    help="Also write nodes.csv, components.csv and totals.csv (units in the headers) to DIR.",
)
@click.option(
    "--units",
    type=click.Choice(["si", "engineering"]),
    default="si",
    show_default=True,
    help="Units of the tables: SI, or engineering (degC, bar, t/h, kJ/kg, MW).",
)
@_COOLPROP_CACHE_OPTION
def steady(plant_file, out_dir, units, coolprop_cache):
    """The plant at rest at its start time: the design-point table (per node p, T, h,
    quality or phase, mass flow; per component duty, power, opening, efficiency; plant
    totals), found by the steady start of `dnasim run` (start = "steady"). Exits 2
    with the reason when the plant has no state at rest inside its components'
    ranges."""
    old = _catch_sigterm()
    try:
        _steady(plant_file, out_dir, units, coolprop_cache)
    except (KeyboardInterrupt, _Terminate) as exc:
        what = "SIGTERM" if isinstance(exc, _Terminate) else "Ctrl-C"
        raise SimulationFailed(f"{plant_file}: steady interrupted ({what})") from None
    finally:
        if old is not None:
            signal.signal(signal.SIGTERM, old)


def _steady(plant_file, out_dir, units, coolprop_cache):
    from dnasim.core.errors import DnasimError, OutputError, PlantError

    _coolprop_cache(coolprop_cache)
    loaded = _load(plant_file)
    try:
        from dnasim.compilation.compiler import compile as compile_plant
        from dnasim.start.steady_state import find_steady_state
        from dnasim.tools.design_point import design_point, format_design_point, write_design_point

        system = compile_plant(loaded.plant)
        t0 = loaded.simulation.t_start
        rest = find_steady_state(system, t0)
        dp = design_point(system, rest, t0)
        click.echo(format_design_point(dp, units=units))
        if out_dir is not None:
            try:
                files = write_design_point(dp, Path(out_dir), units=units)
            except OSError as exc:
                raise OutputError(f"cannot write the tables to {out_dir}: {exc}") from None
            for f in files:
                click.echo(f"wrote {f}")
    except OutputError as exc:
        raise InputError(str(exc)) from None
    except PlantError as exc:
        raise InputError(f"{plant_file}: {exc}") from None
    except DnasimError as exc:
        raise InputError(f"{plant_file}: no state at rest found: {exc}") from None
    except click.ClickException:
        raise
    except Exception as exc:
        located = _located(exc, plant_file)
        if located is not None:
            raise InputError(located) from None
        raise _internal(exc, EXIT_INPUT) from None


# --------------------------------------------------------------------------- components


@main.command(context_settings=CONTEXT_SETTINGS)
@click.argument("name", required=False)
def components(name):
    """List the component library; with NAME, one component's ports, parameters
    (units, defaults, ranges) and equations."""
    from dnasim.core.values import suggest as _suggest
    from dnasim.plant.plantfile import _registry, component_info
    from dnasim.run.runner import format_component

    try:
        registry = _registry()
    except Exception as exc:
        raise _internal(exc, EXIT_INPUT) from None
    if name is None:
        click.echo("Component types (dnasim components NAME for details):\n")
        width = max((len(n) for n in registry), default=0)
        for tname in sorted(registry):
            info = component_info(registry[tname])
            first = info["doc"].splitlines()[0] if info["doc"] else ""
            click.echo(f"  {tname:<{width}}  {first}")
        click.echo("\nTime functions for boundary values and set points (see docs/plant_files.md):")
        click.echo('  { type = "constant", value = V }')
        click.echo('  { type = "step", t0 = T, before = V, after = V }')
        click.echo('  { type = "ramp", t0 = T, t1 = T, start = V, end = V }')
        click.echo('  { type = "table", times = [T, ...], values = [V, ...] }')
        click.echo('  { type = "sine", mean = V, amplitude = dV, period = T, phase = rad }')
        return
    cls = registry.get(name)
    if cls is None:
        lower = {k.lower(): k for k in registry}
        if name.lower() in lower:
            cls = registry[lower[name.lower()]]
        else:
            raise InputError(
                f"unknown component type {name!r}{_suggest(name, registry)} "
                f"(known: {', '.join(sorted(registry))})"
            )
    click.echo(format_component(component_info(cls)))


# --------------------------------------------------------------------------- plot


@main.command(name="plot", context_settings=CONTEXT_SETTINGS)
@click.argument("results_csv", metavar="RESULTS.csv", type=click.Path(dir_okay=False))
@click.argument("patterns", nargs=-1, metavar="[PATTERN]...")
@click.option("--vars", "var_patterns", multiple=True, metavar="PATTERN", help="Variables to plot.")
@click.option(
    "-o",
    "--output",
    "out_file",
    default=None,
    metavar="FILE.png",
    help="Output image [default: variables.png and steps.png next to the CSV, as run --plot].",
)
@_UNITS_OPTION
def plot_cmd(results_csv, patterns, var_patterns, out_file, units):
    """Re-plot saved results: the variables matching the patterns over time, and,
    when steps.csv is next to the CSV, step size and order over time. The same
    files and markers as ``dnasim run --plot``."""
    from dnasim.core.errors import OutputError
    from dnasim.run.output import read_results_csv
    from dnasim.tools.plots import write_run_plots

    path = Path(results_csv)
    try:
        names, units_of, data = read_results_csv(path)
    except FileNotFoundError:
        raise InputError(f"{path}: no such file") from None
    except (OSError, ValueError, StopIteration) as exc:
        raise InputError(f"{path}: not a dnasim results CSV: {exc}") from None
    if not names or names[0] != "time":
        raise InputError(f"{path}: the first column must be 'time [s]'")
    pats = _split_patterns(var_patterns) + list(patterns)
    variables = [n for n in names[1:]]
    try:
        files = write_run_plots(path, pats, units=units, variables_path=out_file)
    except OutputError as exc:
        raise InputError(str(exc)) from None
    except ValueError as exc:
        if str(exc).startswith("no variable matches"):
            raise InputError(
                f"{path}: no variable matches {' '.join(pats)}; variables: "
                + ", ".join(variables[:20])
                + (" ..." if len(variables) > 20 else "")
            ) from None
        # e.g. an image format matplotlib does not know
        raise InputError(f"option --output: cannot write {out_file}: {exc}") from None
    for f in files:
        click.echo(f"wrote {f}")


# --------------------------------------------------------------------------- sweep


@main.command(name="sweep", context_settings=CONTEXT_SETTINGS)
@click.argument("plant_file", metavar="PLANT.toml", type=click.Path(dir_okay=False))
@click.option(
    "-o",
    "--output",
    "out_dir",
    required=True,
    metavar="DIR",
    help="Sweep directory: sweep.nc, summary.csv and one folder per case. A sweep "
    "started again into DIR skips the cases already done there.",
)
@click.option(
    "--set",
    "set_options",
    multiple=True,
    metavar="COMP.PARAM=V1,V2,...",
    help='Values of one parameter, with units, e.g. --set steam.T="500 degC,520 degC" or '
    "--set simulation.t_end=60,120; repeat the option: the cases are the Cartesian product.",
)
@click.option(
    "--cases",
    "cases_file",
    default=None,
    metavar="FILE",
    type=click.Path(dir_okay=False),
    help="Cases from a CSV (header COMP.PARAM or 'COMP.PARAM [unit]', one row per case) "
    "or TOML file ([[case]] tables).",
)
@click.option(
    "-j",
    "--jobs",
    type=click.IntRange(1, 1024),
    default=None,
    help="Local worker processes [default: the number of CPUs].",
)
@click.option(
    "--scheduler",
    default=None,
    metavar="ADDRESS",
    help="Run on an existing Dask distributed cluster, e.g. tcp://127.0.0.1:8786 (tcp:// or "
    "tls://). Only a scheduler you control: Dask exchanges pickles, which run code.",
)
@click.option(
    "--output-interval",
    default=None,
    metavar="DT",
    help='Time between rows of each case and of the time grid of sweep.nc, e.g. "1 s" '
    "[default: the plant file's, else 501 points].",
)
@_COOLPROP_CACHE_OPTION
@_ALLOW_IMPORT_OPTION
@click.option("-q", "--quiet", is_flag=True, help="No progress bar and no summary.")
def sweep_cmd(
    plant_file,
    out_dir,
    set_options,
    cases_file,
    jobs,
    scheduler,
    output_interval,
    coolprop_cache,
    allow_import,
    quiet,
):
    """Run PLANT.toml for many parameter sets: the Cartesian product of --set values,
    or the rows of --cases FILE. Writes DIR/sweep.nc (xarray, every output over case
    and time), DIR/summary.csv (one row per case) and DIR/case_NNNN/ (results.csv,
    events.csv, steps.csv, done.json). A failed case is recorded and the others go on;
    exit code 1 when any case failed."""
    from dnasim.core.errors import OutputError
    from dnasim.plant.cases import (
        CaseError,
        check_cases,
        parse_set_option,
        product_cases,
        read_cases,
    )

    _coolprop_cache(coolprop_cache)
    loaded = _load(plant_file, allow_import)
    if bool(set_options) == bool(cases_file):
        raise InputError("give the cases with --set COMP.PARAM=V1,V2,... or with --cases FILE")
    try:
        if cases_file:
            cases = read_cases(cases_file)
        else:
            values = {}
            for opt in set_options:
                key, vals = parse_set_option(opt)
                if key in values:
                    raise CaseError(f"{key}: given twice; list all values in one --set")
                values[key] = vals
            cases = product_cases(values)
        check_cases(loaded.spec, cases)
    except CaseError as exc:
        where = f"option --cases {cases_file}" if cases_file else "option --set"
        raise InputError(f"{where}: {exc}") from None
    if not cases:
        raise InputError(f"{cases_file}: no cases")
    dt = _parse_option_quantity(output_interval, "s", "--output-interval")
    from dnasim.tools.sweeps import check_output_sizes, sweep

    try:
        spec = loaded.spec
        if dt is not None:
            import copy

            spec = copy.deepcopy(spec)
            spec.simulation.output_interval = dt
            spec.simulation.t_eval = None  # the option replaces the file's output times
        check_output_sizes(spec, cases, dt)
    except CaseError as exc:
        src = "option --output-interval" if dt is not None else plant_file
        raise InputError(f"{src}: {exc}") from None
    address = _scheduler_address(scheduler) if scheduler else None
    out = Path(out_dir)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise InputError(
            f"cannot create the output directory {out}: {exc.strerror or exc}"
        ) from None

    progress = not quiet and sys.stdout.isatty()
    client = None
    try:
        if address:
            try:
                from dask.distributed import Client
            except ImportError:
                raise InputError(
                    "option --scheduler needs dask.distributed, an optional dependency: "
                    "pip install 'dnasim[dask]'"
                ) from None
            try:
                client = Client(address, timeout=10)
            except Exception as exc:  # refused, timed out, a scheme dask cannot use
                raise InputError(
                    f"option --scheduler: cannot connect to {address}: {type(exc).__name__}: {exc}"
                ) from None
            executor = client.get_executor()
        else:
            n = jobs or os.cpu_count() or 1
            executor = None if n == 1 else _process_pool(min(n, len(cases)))
        try:
            result = sweep(
                loaded.spec, cases, executor, out_dir=out, output_interval=dt, progress=progress
            )
        except BaseException:
            # an interrupt or an output error: the running cases are not waited for
            stop = getattr(executor, "terminate_workers", None)
            if stop is not None:
                stop()
            raise
        finally:
            if executor is not None and client is None:
                executor.shutdown(cancel_futures=True)
    except click.ClickException:
        raise
    except OutputError as exc:
        raise InputError(str(exc)) from None
    except KeyboardInterrupt:
        raise SimulationFailed(
            f"sweep interrupted; the cases finished so far are in {out} (start the same "
            "command again to run the others)"
        ) from None
    except Exception as exc:
        raise _internal(exc, EXIT_SIMULATION) from None
    finally:
        if client is not None:
            client.close()
    if result.changed:
        click.echo(
            f"dnasim: note: {result.changed} of the cases in {out} had been run with another "
            "plant or other settings (the plant file, its parameters or --output-interval "
            "changed since): they were run again",
            err=True,
        )
    if not quiet:
        click.echo(
            f"{len(cases)} cases: ran {result.ran}, skipped {result.skipped} (done before), "
            f"failed {result.failed}\nresults in {out} (sweep.nc, summary.csv, case_NNNN/)"
        )
    full = result.summary[result.summary["status"] == "output-error"]
    if len(full):
        first = full.iloc[0]
        raise InputError(
            f"{len(full)} of {len(cases)} cases could not write their results (case "
            f"{first['case']}: {first['message']}); the other cases are in {out}. Free disk "
            "space (or raise the file size limit) and start the same command again: the "
            "cases that are done are skipped, these run again"
        )
    if result.failed:
        bad = result.summary[result.summary["status"] != "finished"]
        lines = [f"case {r.case}: {r.status}: {r.message}" for r in bad.itertuples()]
        raise SimulationFailed(
            f"{result.failed} of {len(cases)} cases failed:\n" + "\n".join(lines[:20])
        )


def _process_pool(n: int):
    """``n`` local worker processes (spawned: no threads of this process are copied)
    that exit when this process dies (``dnasim.tools.sweeps.LocalPool``)."""
    from dnasim.tools.sweeps import local_pool

    return local_pool(n)


#: schemes of Dask's communication layer that reach a scheduler over the network
SCHEDULER_SCHEMES = ("tcp", "tls")
_HOST_LABEL = re.compile(r"^(?!-)[A-Za-z0-9-]{1,63}(?<!-)$")


def _scheduler_address(text: str) -> str:
    """``--scheduler``: ``[tcp://|tls://]HOST:PORT`` with a host name, an IPv4
    address or a bracketed IPv6 address and a port 1..65535; returns the address
    with its scheme. Raises ``InputError`` saying what is wrong."""
    import ipaddress

    def bad(why):
        return InputError(
            f"option --scheduler {text[:80]!r}{'...' if len(text) > 80 else ''}: {why}; "
            "expected the address of a Dask scheduler, e.g. tcp://127.0.0.1:8786 or "
            "tls://scheduler.example.org:8786"
        )

    raw = text.strip()
    scheme, sep, rest = raw.partition("://")
    if not sep:
        scheme, rest = "tcp", raw
    scheme = scheme.lower()
    if scheme not in SCHEDULER_SCHEMES:
        known = ", ".join(f"{x}://" for x in SCHEDULER_SCHEMES)
        raise bad(f"the scheme '{scheme}://' is not one of {known}")
    if not rest or any(c in rest for c in "/?#@ \t"):
        raise bad("no host and port, or a path, user or query in it")
    if rest.startswith("["):
        host, close, tail = rest[1:].partition("]")
        if not close:
            raise bad("an IPv6 address without its closing ']'")
        try:
            ipaddress.IPv6Address(host)
        except ValueError:
            raise bad(f"'{host}' is not an IPv6 address") from None
        if not tail.startswith(":"):
            raise bad("no port (write [::1]:8786)")
        port = tail[1:]
        shown = f"[{host}]"
    else:
        host, colon, port = rest.rpartition(":")
        if not colon:
            raise bad("no port (write HOST:8786)")
        if ":" in host:
            raise bad("an IPv6 address must be in brackets, [::1]:8786")
        if len(host) > 253:
            raise bad(f"the host name has {len(host)} characters, more than the 253 DNS allows")
        if not all(_HOST_LABEL.match(x) for x in host.split(".")):
            raise bad("the host is not a host name or an IPv4 address")
        shown = host
    if not port.isdigit() or not 1 <= int(port) <= 65535:
        raise bad(f"the port '{port[:20]}' is not a number from 1 to 65535")
    return f"{scheme}://{shown}:{int(port)}"


# --------------------------------------------------------------------------- linearize


@main.command(context_settings=CONTEXT_SETTINGS)
@click.argument("plant_file", metavar="PLANT.toml", type=click.Path(dir_okay=False))
@click.option(
    "--inputs",
    "inputs",
    required=True,
    metavar="LIST",
    help="Comma-separated inputs: parameters (steam.T) or signals held as inputs (spray_valve.z).",
)
@click.option(
    "--outputs", "outputs", required=True, metavar="LIST", help="Comma-separated results names."
)
@click.option(
    "--at",
    "at",
    default="steady",
    metavar="steady|T",
    help='Operating point: the steady state, or the simulated state at time T (e.g. "5 min").',
)
@click.option(
    "-o", "--output", "out_dir", default=None, metavar="DIR", help="Write linear.npz/.mat here."
)
@click.option("--all-states", is_flag=True, help="Keep states no output depends on.")
@_ALLOW_IMPORT_OPTION
def linearize(plant_file, inputs, outputs, at, out_dir, all_states, allow_import):
    """Linearise PLANT.toml: x' = A x + B u, y = C x + D u; print eigenvalues, time
    constants, damping and DC gains; with -o write linear.npz (+ linear_A.npz ...,
    scipy.sparse) and linear.mat."""
    from dnasim.core.errors import DnasimError
    from dnasim.tools.linearize import linearize as _linearize

    loaded = _load(plant_file, allow_import)
    t = None if at.strip().lower() == "steady" else _parse_option_quantity(at, "s", "--at")
    try:
        lm = _linearize(
            loaded,
            _split_patterns([inputs]),
            _split_patterns([outputs]),
            t=t,
            keep_all_states=all_states,
        )
    except DnasimError as exc:
        raise InputError(f"{plant_file}: {exc}") from None
    click.echo(lm.summary())
    if out_dir:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        for f in (lm.save_npz(out / "linear.npz"), lm.save_mat(out / "linear.mat")):
            click.echo(f"wrote {f}")


@main.command(name="fmu", context_settings=CONTEXT_SETTINGS)
@click.argument("plant_file", metavar="PLANT.toml", type=click.Path(dir_okay=False))
@click.option(
    "-o", "--output", "out_file", default=None, metavar="FILE", help="The FMU (default PLANT.fmu)."
)
@click.option(
    "--inputs",
    "inputs",
    default=None,
    metavar="LIST",
    help="Comma-separated parameters as FMU inputs (steam.T,pi.setpoint); default: every "
    "boundary value, set point and opening of the plant.",
)
@click.option(
    "--vars",
    "var_patterns",
    multiple=True,
    metavar="PATTERN",
    help="Outputs (names or patterns as run --vars); default: the signal outputs.",
)
def fmu_cmd(plant_file, out_file, inputs, var_patterns):
    """Export PLANT.toml as an FMI 2.0 co-simulation FMU (pythonfmu; it needs Python
    with dnasim at run time, docs/fmu.md)."""
    from dnasim.core.errors import DnasimError
    from dnasim.tools.fmu import build_fmu

    loaded = _load(plant_file)
    out = Path(out_file) if out_file else Path(plant_file).with_suffix(".fmu")
    patterns = _split_patterns(var_patterns) or None
    try:
        path = build_fmu(
            plant_file,
            out,
            _split_patterns([inputs]) if inputs is not None else None,
            patterns,
            loaded=loaded,
        )
    except DnasimError as exc:
        raise InputError(f"{plant_file}: {exc}") from None
    except OSError as exc:
        raise InputError(f"{plant_file}: cannot write {out}: {exc.strerror or exc}") from None
    from dnasim.tools.fmu import read_interface

    iface = read_interface(path)
    for note in iface.get("notes", ()):
        click.echo(f"dnasim: note: {note}", err=True)
    click.echo(
        f"wrote {path}: FMI 2.0 co-simulation, {len(iface['inputs'])} inputs "
        f"({', '.join(iface['inputs']) or 'none'}), {len(iface['outputs'])} outputs "
        f"({', '.join(iface['outputs'])})"
    )


# --------------------------------------------------------------------------- upgrade


@main.command(context_settings=CONTEXT_SETTINGS)
@click.argument("plant_file", metavar="PLANT.toml", type=click.Path(dir_okay=False))
@click.option(
    "-o", "--output", "out_file", default=None, metavar="NEW.toml", help="Write the new file here."
)
@click.option("--in-place", is_flag=True, help="Rewrite PLANT.toml itself.")
def upgrade(plant_file, out_file, in_place):
    """Rewrite PLANT.toml in the current plant-file format ([plant] format = 2):
    renamed keys, the old sink sign, old defaults the file relied on. Comments and
    layout are kept; each change is printed (stderr) with its table, key and line.
    Without -o or --in-place the new file goes to stdout."""
    from dnasim.core.errors import OutputError, PlantError
    from dnasim.plant.migrations import upgrade_text
    from dnasim.run.output import _atomic_write

    if out_file and in_place:
        raise InputError("give -o NEW.toml or --in-place, not both")
    path = Path(plant_file)
    try:
        text = path.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise InputError(f"{path}: no such plant file") from None
    except UnicodeDecodeError:
        raise InputError(f"{path}: not a UTF-8 text file; save the plant file as UTF-8") from None
    except OSError as exc:
        raise InputError(f"{path}: cannot read the plant file: {exc.strerror or exc}") from None
    try:
        new, changes, reviews = upgrade_text(text, str(path))
    except PlantError as exc:
        raise InputError(str(exc)) from None
    for line in changes:
        click.echo(f"dnasim: upgrade: {line}", err=True)
    for line in reviews:
        click.echo(f"dnasim: {line}", err=True)
    if not changes:
        click.echo(f"dnasim: upgrade: {path} is already in the current format", err=True)
    target = path if in_place else Path(out_file) if out_file else None
    if target is None:
        click.echo(new, nl=False)
        return
    if not changes and target == path:
        return
    try:
        mode = target.stat().st_mode & 0o7777 if target.exists() else None
        _atomic_write(target, lambda f: f.write(new.encode("utf-8")))
        if mode is not None:
            os.chmod(target, mode)  # the temporary file's 0600 is not the plant file's
    except OutputError as exc:
        raise InputError(str(exc)) from None
    except OSError as exc:
        raise InputError(f"cannot write {target}: {exc.strerror or exc}") from None
    click.echo(f"dnasim: upgrade: wrote {target}", err=True)


if __name__ == "__main__":  # pragma: no cover
    from dnasim.cli.entry import main as _main

    sys.exit(_main())
