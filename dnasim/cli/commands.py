"""The ``dnasim`` command: run, steady, sweep, check, components, plot, linearize, fmu.

Exit codes: 0 success; 1 the simulation failed or was interrupted (results up to
that time are on disk); 2 bad input (plant file, options, paths).

Heavy modules (numpy, the solver, CoolProp, matplotlib) are imported inside the
commands, so ``dnasim --help`` starts fast.
"""

from __future__ import annotations

import os
import signal
from pathlib import Path

import click

from dnasim.cli import sweep_command as _sweep_command  # noqa: F401  (registers `sweep`)
from dnasim.cli.base import (
    CONTEXT_SETTINGS,
    EXIT_INPUT,
    InputError,
    SimulationFailed,
    _internal,
    _load,
    _located,
    _parse_option_quantity,
    _split_patterns,
    main,
)
from dnasim.cli.run_command import (
    _ALLOW_IMPORT_OPTION,
    _COOLPROP_CACHE_OPTION,
    _UNITS_OPTION,
    _catch_sigterm,
    _coolprop_cache,
)
from dnasim.core.interrupts import Terminated as _Terminate

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
