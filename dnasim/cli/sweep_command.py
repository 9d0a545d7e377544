"""``dnasim sweep``: many cases of one plant on local processes or a Dask cluster."""

from __future__ import annotations

import os
import re
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
    _parse_option_quantity,
    main,
)
from dnasim.cli.run_command import (
    _ALLOW_IMPORT_OPTION,
    _COOLPROP_CACHE_OPTION,
    _coolprop_cache,
)


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
