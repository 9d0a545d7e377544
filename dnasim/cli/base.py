"""The ``dnasim`` command group and what its commands share: the exit codes, the
one-paragraph input error (exit 2), plant loading with located messages, option
quantities with units, the optional extras' check."""

from __future__ import annotations

import os
import traceback

import click

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
