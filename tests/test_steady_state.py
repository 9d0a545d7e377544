"""The steady start (issue 20, ``dnasim.start.steady_state``): plants written as a user
writes them, each started at rest and checked against a long given-start run settled
to rest (the time functions are constant before t0, so a run from t0 - T to t0 ends
at the state at rest of t0) or against hand values with IF97 (CoolProp's IF97
backend); the set-ups without a state at rest inside the components' ranges stop
with their message; node guesses; the design-point table of ``dnasim steady``.

Every plant here failed on 834cc95 (its steady start said "no steady state found",
"singular Jacobian", or exited 0 with a controller output outside [0, 1]; its given
start of the feed line found a steam-bound state), unless a test says otherwise (the
superheater with sprays and the saturated spray: regression tests).
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from CoolProp.CoolProp import PropsSI

from dnasim.cli.commands import main
from dnasim.plant.plantfile import load, loads
from dnasim.run.simulation import simulate
from dnasim.start.steady_state import SteadyStateError, find_steady_state

ROOT = Path(__file__).resolve().parents[1]
PLANTS = ROOT / "tests" / "plants"
WATER = "IF97::Water"


def invoke(*args):
    result = CliRunner().invoke(main, [str(a) for a in args], catch_exceptions=True)
    if result.exception is not None and not isinstance(result.exception, SystemExit):
        raise result.exception  # a Python traceback is a bug
    return result


def compiled(name):
    loaded = load(PLANTS / f"{name}.toml")
    return loaded.plant.compile()


def settled(system, T, names):
    """The given start run from -T to 0 s (rtol, atol_scaled 1e-8): the values of
    ``names`` at its end."""
    res = simulate(
        system, t0=-T, t_end=0.0, start="given", rtol=1e-8, atol_scaled=1e-8, t_eval=[-T, 0.0]
    )
    assert res.success, res.message
    return {n: float(res[n][-1]) for n in names}


def assert_settled_equal(system, rest, ref, rel):
    at = system.index
    for name, value in ref.items():
        scale = max(abs(value), system.nominal[at[name]])
        assert abs(rest.y[at[name]] - value) <= rel * scale, (name, rest.y[at[name]], value)


# ------------------------------------------------------------------ plants with a state at rest


def test_drum_level_control_starts_at_rest():
    # On 834cc95: Newton ended near 1 bar with node enthalpies outside IF97 ("no
    # steady state found"), although p0 = 99 bar is given. Now: found from the march
    # (the feed's enthalpy reaches the drum, not the drum's the feed node).
    system = compiled("steady_drum_level")
    rest = find_steady_state(system, 0.0)
    at = system.index
    p, m = rest.y[at["drum.p"]], rest.y[at["feed.m"]]
    # hand values, IF97: the steam flow is the feed flow and carries the heat,
    # m (h''(p) - h(p_feed, 150 degC)) = Q; the level controller holds 2.5 m, its
    # output is m / m_scale; the valve passes m = C sqrt(p - p_hdr) (dp >> dp_reg).
    # Tolerances: 1e-8 relative, the start's Newton (1e-9 of each scale) with margin;
    # the feed is a liquid at the drum's pressure (the mass-flow boundary's node)
    h_v = PropsSI("H", "P", p, "Q", 1, WATER)
    h_f = PropsSI("H", "P", rest.y[at["n_feed.p"]], "T", 423.15, WATER)
    assert m * (h_v - h_f) == pytest.approx(100e6, rel=1e-8)
    assert rest.y[at["drum.level"]] == pytest.approx(2.5, rel=1e-9)
    assert rest.y[at["level_pi.z"]] == pytest.approx(m / 100.0, rel=1e-9)
    assert m == pytest.approx(0.0165 * np.sqrt(p - 1e5), rel=1e-8)
    assert rest.saturated == []
    assert any("'steam_valve'" in n and "choked" in n for n in rest.notes)  # 90 bar -> 1 bar
    # the given start (p0 = 99 bar, V_l0 = 25 m3) settles to the same state: after
    # 30000 s the level loop's slowest mode (~Kp/KI = 100 s, the drum's storage ~1000 s)
    # has decayed below 1e-5 of each variable's scale
    names = ["drum.p", "drum.V_l", "drum.M", "feed.m", "level_pi.z", "n_steam.h"]
    assert_settled_equal(system, rest, settled(system, 30000.0, names), rel=1e-5)


def test_prv_station_starts_at_rest():
    # On 834cc95: "singular Jacobian", with a hint that the consumer is choked, from
    # an iterate with the LP side at 100 bar. Now the PI's set point guesses the LP
    # header (12 bar) and the pressures spread through the pipes before the valves.
    system = compiled("steady_prv_station")
    rest = find_steady_state(system, 0.0)
    at = system.index
    assert rest.y[at["n_lp_out.p"]] == pytest.approx(12e5, rel=1e-9)  # the set point
    z = rest.y[at["p_pi.z"]]
    assert 0.0 < z < 1.0 and rest.saturated == []
    flows = [rest.y[at[n]] for n in ("boiler.m", "nrv.m", "prv.m", "consumer.m")]
    np.testing.assert_allclose(flows, flows[0], rtol=1e-9)  # one flow, at rest
    # against the given start (every pipe at its guessed state) settled over 10000 s:
    # the PI's integral time 20 s, the line's storage ~ s: decayed far below 1e-6
    names = ["n_lp.p", "n_nrv.p", "p_pi.z", "consumer.m", "n_lp_out.h", "lp_header.M[1]"]
    assert_settled_equal(system, rest, settled(system, 10000.0, names), rel=1e-6)


def test_feed_line_given_start_feeds_and_settles_at_the_steady_start():
    # On 834cc95 the given start found a steam-bound state: the pump outlet at the
    # drum's pressure with hot water, 0.003 kg/s of feed, and the run died at 28 s; its
    # steady start stopped with the level controller "beyond its switch". Now the given
    # start's pump delivers (its water reaches the drum), and the run settles at the
    # steady start (found by the pseudo-transient continuation).
    loaded = load(PLANTS / "steady_feed_line.toml")
    system = loaded.plant.compile()
    from dnasim.start.initial import initial_values

    y0, _ = initial_values(system, 0.0, "given")
    at = system.index
    assert y0[at["pump.m"]] > 20.0  # kg/s: the pump feeds (nominal 30 kg/s)
    h_pump = y0[at["n_pump.h"]]
    assert PropsSI("T", "P", y0[at["n_pump.p"]], "H", h_pump, WATER) < 430.0  # 150 degC water
    rest = find_steady_state(system, 0.0)
    # IF97 hand values at rest: the steam carries the heat, m (h''(p) - h_feed) = Q,
    # the feed leaving the pump is the suction's water plus the pump's work (at rest
    # the throttling valves keep h); 1e-8: the start's Newton tolerance with margin
    p, m = rest.y[at["drum.p"]], rest.y[at["pump.m"]]
    h_feed = rest.y[at["n_feed.h"]]
    assert m * (PropsSI("H", "P", p, "Q", 1, WATER) - h_feed) == pytest.approx(75e6, rel=1e-8)
    assert h_feed == pytest.approx(rest.y[at["pump.h_2"]], rel=1e-12)
    # the given start settled over 30000 s (the level loop's and the drum's slowest
    # modes, ~1000 s, decayed below 1e-5)
    names = ["drum.p", "drum.V_l", "pump.m", "level_pi.z", "n_nrv.p", "n_feed.h"]
    assert_settled_equal(system, rest, settled(system, 30000.0, names), rel=1e-5)


def test_valve_chain_without_volumes_starts():
    # Four restrictions in series, no volume between them. On 834cc95 the given start
    # stopped with a singular Jacobian (every node guessed at the line's 160 bar: the
    # check valve in its closed band). Now the given start (the same state as the
    # steady one: every variable is algebraic) is found.
    from dnasim.start.initial import initial_values

    system = compiled("valve_chain_check")
    y, _ = initial_values(system, 0.0, "given")
    at = system.index
    m = y[at["line.m"]]
    for name in ("isolation", "throttle", "nrv", "control"):
        assert y[at[f"{name}.m"]] == pytest.approx(m, rel=1e-9)
    # the two plain valves' law written out, m = C z_e dp / (dp^2 + dp_reg^2)^(1/4)
    # (z_e = 1e-6 + (1 - 1e-6) z, dp_reg = 10 Pa: 1e-7 of the isolation valve's 0.15 bar):
    # the start's pressures satisfy it to its tolerance
    for name, C, z, a, b in (
        ("isolation", 0.0082, 0.36, "n_line", "n_a"),
        ("throttle", 3.2e-4, 0.28, "n_a", "n_b"),
    ):
        dp = y[at[f"{a}.p"]] - y[at[f"{b}.p"]]
        law = C * (1e-6 + (1 - 1e-6) * z) * dp / (dp * dp + 100.0) ** 0.25
        assert m == pytest.approx(law, rel=1e-9), name
    rest = find_steady_state(system, 0.0)
    np.testing.assert_allclose(rest.y[: system.n_node_vars], y[: system.n_node_vars], rtol=1e-8)


def test_superheater_sprays_hold_their_set_points_by_hand_balances():
    # flue gas through two exchangers, two sprays under PI control (z1 = 0.51, z2 =
    # 0.45). Checked by hand with IF97: each attemperator mixes to its set point, its
    # energy balance closes, each exchanger passes the gas's enthalpy drop to the steam
    system = compiled("steady_superheater_sprays")
    rest = find_steady_state(system, 0.0)
    y, at = rest.y, system.index
    T_att1 = PropsSI("T", "P", y[at["n_att1.p"]], "H", y[at["n_att1.h"]], WATER)
    T_att2 = PropsSI("T", "P", y[at["n_att2.p"]], "H", y[at["n_att2.h"]], WATER)
    # the set points, to 10 mK: IF97's backward equations T(p, h) of region 2 agree with
    # its basic equation to 10 mK (IAPWS-IF97, 2007, table 2), and dnasim's and
    # CoolProp's IF97 differ by up to 4 mK here
    assert T_att1 == pytest.approx(693.15, abs=0.01)
    assert T_att2 == pytest.approx(793.15, abs=0.01)
    for att, steam, spray in (("att1", "n_sh1", "n_spray1"), ("att2", "n_sh2", "n_spray2")):
        ms, mw, mo = (y[at[f"{att}.{v}"]] for v in ("m_steam", "m_water", "m_out"))
        assert mo == pytest.approx(ms + mw, rel=1e-10)
        mixed = (ms * y[at[f"{steam}.h"]] + mw * y[at[f"{spray}.h"]]) / mo
        assert mixed == pytest.approx(y[at[f"{att}.h_v"]], rel=1e-10)  # adiabatic mixing
    gas = next(b.comp.side_medium("hot") for b in system.blocks if b.comp.name == "sh1")
    for hx, g_in, g_out in (("sh1", "g_mid", "g_eco"), ("sh2", "g_in", "g_mid")):
        b = system.block(hx)
        x = b.local(y)
        m_gas = float(x["hot_m"][0])
        dh_gas = y[at[f"{g_in}.h"]] - y[at[f"{g_out}.h"]]
        duty = -float(np.sum(x["cold_Q"]))
        assert m_gas * dh_gas == pytest.approx(duty, rel=1e-8)  # gas side = steam side
        assert duty > 1e6 and gas.label != "Water (IF97)"
    assert 0.2 < y[at["pi1.z"]] < 0.8 and 0.2 < y[at["pi2.z"]] < 0.8


@pytest.mark.field_slow
def test_superheater_sprays_given_start_settles_at_the_steady_start():
    # the given start (exchangers at hot_T0/cold_T0, the gas pressures of [nodes.*])
    # run for 3000 s: its transient has decayed below 1e-7 of each scale (the PIs'
    # integral times 50 s; the walls' 8 MJ/K over ~300 kW/K: ~30 s). 985 steps, ~20 s
    system = compiled("steady_superheater_sprays")
    rest = find_steady_state(system, 0.0)
    names = ["pi1.z", "pi2.z", "n_sh1.h", "n_sh2.h", "g_eco.h", "valve1.m", "drum.m"]
    assert_settled_equal(system, rest, settled(system, 3000.0, names), rel=1e-6)


def test_saturated_spray_at_rest_matches_the_settled_run(tmp_path):
    # plants/attemperator.toml with a spray valve a tenth the size: to hold 450 degC
    # the controller would need z > 1. (834cc95 found this state too, for this
    # PIDController; for the PIController, whose held integral no equation reads when
    # saturated, it said "no steady state found": tests/test_faults.py.) The limit
    # engages, the steam stays above the set point and the back-calculation keeps v just
    # above z_max (v - z_max = T_t Kp e / T_i at rest): a state at rest with the
    # controller saturated, the one a long given start settles at
    text = (ROOT / "plants" / "attemperator.toml").read_text()
    text = text.replace('C = "0.002 kg/(s.Pa0.5)"', 'C = "0.0002 kg/(s.Pa0.5)"')
    system = loads(text, "saturated.toml").plant.compile()
    rest = find_steady_state(system, 0.0)
    at = system.index
    assert rest.saturated == [("pi", "high")] and rest.y[at["pi.z"]] == 1.0
    assert rest.y[at["pi.e"]] > 1.0  # K above the set point
    assert any("'pi' holds its output at z_max" in n for n in rest.notes)
    # the given start's run over 5000 s settles at the same state (the controller
    # saturates during the run, as the steady start engaged it); 1e-6 of each scale
    names = ["pi.z", "pi.v", "spray_valve.m", "n_mix.h", "att.T", "n_line.p"]
    assert_settled_equal(system, rest, settled(system, 5000.0, names), rel=1e-6)


# ------------------------------------------------------------------ no state at rest


def _attemperator(**replace) -> str:
    text = (ROOT / "plants" / "attemperator.toml").read_text()
    for old, new in replace.items():
        assert old in text, old
        text = text.replace(old, new)
    return text


SPRAY_BELOW = {'p = "150 bar"': 'p = "80 bar"'}  # spray water below the 120 bar steam
TURBINE = 'p = "{}"\nports = {{ port = "n_turbine" }}'
SINK_ABOVE = {TURBINE.format("100 bar"): TURBINE.format("130 bar")}  # above the steam's 120 bar


def test_spray_below_the_steam_pressure_has_no_state_at_rest(tmp_path):
    # On 834cc95: the steady start put the PI output at z = -0.445 (outside [0, 1]), the
    # spray flowed uphill, then steam flowed back into the spray line all run: exit 0.
    # Now: the output at rest without limits is -0.445, below z_min = 0; at z_min the
    # steam is too hot and the controller would open again: no mode balances
    system = loads(_attemperator(**SPRAY_BELOW), "spray.toml").plant.compile()
    with pytest.raises(SteadyStateError) as info:
        find_steady_state(system, 0.0)
    msg = str(info.value)
    for words in ("controller 'pi'", "-0.4447", "z_min = 0", "no mode balances", "'spray_valve'",
                  "80 bar", "flows backwards"):  # fmt: skip
        assert words in msg, (words, msg)
    path = tmp_path / "spray.toml"
    path.write_text(_attemperator(**SPRAY_BELOW))
    res = invoke("run", path, "-o", tmp_path / "out", "-q")
    assert res.exit_code == 2, res.output
    assert "controller 'pi'" in res.output and "Traceback" not in res.output
    assert not (tmp_path / "out" / "results.csv").exists()  # nothing computed, nothing left


def test_sink_above_the_plant_pressure_has_no_state_at_rest(tmp_path):
    # On 834cc95: z = 25.7 and 22 kg/s entered the plant through the sink-only turbine
    # boundary at 130 bar, exit 0 (its switch fires on a sign change only). Now the sink
    # feeding the plant is named, with its flow
    system = loads(_attemperator(**SINK_ABOVE), "sink.toml").plant.compile()
    with pytest.raises(SteadyStateError) as info:
        find_steady_state(system, 0.0)
    msg = str(info.value)
    assert msg.index("boundary 'turbine'") < msg.index("controller 'pi'")  # the cause first
    for words in ("is a sink only", "kg/s would enter the plant", "130 bar"):
        assert words in msg, (words, msg)
    path = tmp_path / "sink.toml"
    path.write_text(_attemperator(**SINK_ABOVE))
    res = invoke("steady", path)
    assert res.exit_code == 2 and "boundary 'turbine'" in res.output, res.output


def test_no_state_at_rest_names_the_balance_that_does_not_close(tmp_path):
    # the feed line's steam valve a third the size: the drum pressure would rise above
    # the pump's shut-off head (no state at rest below it), the continuation stops;
    # the message names the balances still moving and what to try, never the solver's
    # advice to "pass them as algebraic"
    text = (PLANTS / "steady_feed_line.toml").read_text().replace("0.0114 kg", "0.0036 kg")
    text = text.replace('start = "given"', 'start = "steady"')
    system = loads(text, "feed.toml").plant.compile()
    with pytest.raises(SteadyStateError) as info:
        find_steady_state(system, 0.0)
    msg = str(info.value)
    assert "does not balance" in msg and "drum." in msg, msg
    assert "[nodes.<node>]" in msg and 'start = "given"' in msg
    assert "algebraic" not in msg


# ------------------------------------------------------------------ node guesses


PRV_GUESS = '\n[nodes.n_lp]\np = "12 bar"\nT = "300 degC"\n'


def test_node_guess_of_the_plant_file_is_the_start_of_the_search():
    # with the LP header guessed at 12 bar the first guess converges, to the same state
    # as the search without guesses (which, since the half-open check-valve guess of
    # the pumps branch, may converge from its first guess too; on the steady branch
    # alone it needed the march, stage 1c)
    text = (PLANTS / "steady_prv_station.toml").read_text()
    plain = loads(text, "prv.toml").plant.compile()
    guessed_spec = loads(text + PRV_GUESS, "prv.toml")
    guessed = guessed_spec.plant.compile()
    assert guessed_spec.spec.nodes == {"n_lp": {"p": 12e5, "T": 573.15}}
    assert guessed.node_guesses == {"n_lp": {"p": 12e5, "T": 573.15}}
    a, b = find_steady_state(plain, 0.0), find_steady_state(guessed, 0.0)
    assert a.stats.method.startswith("newton") and b.stats.method == "newton (guess)"
    np.testing.assert_allclose(b.y, a.y, rtol=1e-8, atol=1e-8 * plain.nominal.max())


def test_node_guess_from_python():
    from dnasim.start.guess import initial_guess

    plant = load(PLANTS / "steady_prv_station.toml").plant
    plant.guess_node("n_lp", p="12 bar", h="3000 kJ/kg")
    system = plant.compile()
    y = initial_guess(system, 0.0, steady=True)
    k = system.node_index["n_lp"]
    assert (y[k], y[k + 1]) == (12e5, 3e6)
    plant.guess_node("n_nowhere", p="1 bar")
    with pytest.raises(Exception, match="node guess for 'n_nowhere'"):
        plant.compile()
    with pytest.raises(Exception, match="give T or h"):
        plant.guess_node("n_lp", T="500 K", h=1e6)
    with pytest.raises(Exception, match="temperature"):
        plant.guess_node("n_lp", T="5 bar")


@pytest.mark.parametrize(
    "table, words",
    [
        ('[nodes.n_lpx]\np = "12 bar"\n', ["unknown node 'n_lpx'", "did you mean 'n_lp'", "line"]),
        ('[nodes.n_lp]\npressure = "12 bar"\n', ["unknown key", "p (pressure)", "line"]),
        ('[nodes.n_lp]\np = "12 K"\n', ["[nodes.n_lp]", "key 'p'", "pressure"]),
        ('[nodes.n_lp]\np = "12 bar"\nT = "500 K"\nh = 3e6\n', ["give T or h"]),
    ],
)
def test_bad_node_guesses_are_located(tmp_path, table, words):
    path = tmp_path / "prv.toml"
    path.write_text((PLANTS / "steady_prv_station.toml").read_text() + "\n" + table)
    res = invoke("check", path)
    assert res.exit_code == 2, res.output
    for w in words:
        assert w in res.output, (w, res.output)
    assert "Traceback" not in res.output


# ------------------------------------------------------------------ dnasim steady


def test_dnasim_steady_rankine_table_closes_and_matches_the_hand_cycle(tmp_path):
    # the closed cycle's inventory is not fixed by the steady equations: the
    # continuation keeps the given start's; the tables' totals close the water loop's
    # energy balance and the efficiency is the hand calculation's (tests/test_rankine.py)
    res = invoke("steady", ROOT / "plants" / "rankine.toml", "-o", tmp_path)
    assert res.exit_code == 0, res.output
    for words in ("Nodes", "Components", "Plant totals", "cycle efficiency", "n_live"):
        assert words in res.output
    with open(tmp_path / "nodes.csv", newline="") as f:
        nodes = {r["name"]: r for r in csv.DictReader(f)}
    with open(tmp_path / "components.csv", newline="") as f:
        comps = {r["name"]: r for r in csv.DictReader(f)}
    with open(tmp_path / "totals.csv", newline="") as f:
        totals = {r["quantity"]: float(r["value"]) for r in csv.DictReader(f)}
    live = nodes["n_live"]
    p3, T3, h3 = (float(live[k]) for k in ("p [Pa]", "T [K]", "h [J/kg]"))
    assert live["x / phase"] == "superheated" and nodes["n_hotwell"]["x / phase"] == "subcooled"
    assert 0.0 < float(nodes["n_exhaust"]["x / phase"]) < 1.0  # wet exhaust
    # the table's T is IF97's T(p, h): 10 mK, the consistency of IF97's region-2
    # backward equation (IAPWS-IF97, 2007; dnasim's and CoolProp's differ by 1.3 mK here)
    assert PropsSI("T", "P", p3, "H", h3, WATER) == pytest.approx(T3, abs=0.01)
    # the water loop at rest: heat in - heat rejected = net power (1e-8: the start's
    # Newton tolerance on the flows and enthalpies)
    assert totals["heat in"] - totals["heat rejected"] == pytest.approx(
        totals["net power"], rel=1e-8
    )
    assert totals["net power"] == pytest.approx(
        -float(comps["turbine"]["power [W]"]) - float(comps["pump"]["power [W]"]), rel=1e-10
    )
    # the hand cycle of tests/test_rankine.py on the table's pressures and live steam
    eta_p, eta_t = float(comps["pump"]["efficiency [-]"]), float(comps["turbine"]["efficiency [-]"])
    p1, p2 = float(nodes["n_hotwell"]["p [Pa]"]), float(nodes["n_pump"]["p [Pa]"])
    p4 = float(nodes["n_exhaust"]["p [Pa]"])
    h1 = PropsSI("H", "P", p4, "Q", 0, WATER)  # condensate at the shell's pressure
    h2 = h1 + (p2 - p1) / (PropsSI("D", "P", p1, "H", h1, WATER) * eta_p)
    s3 = PropsSI("S", "P", p3, "H", h3, WATER)
    h4 = h3 - eta_t * (h3 - PropsSI("H", "P", p4, "S", s3, WATER))
    eta_hand = ((h3 - h4) - (h2 - h1)) / (h3 - h2)
    # 1e-3: as tests/test_rankine.py (the condensate is drawn slightly subcooled, the
    # pump's work at its own density)
    assert totals["cycle efficiency"] == pytest.approx(eta_hand, rel=1e-3)
    for f in ("nodes.csv", "components.csv", "totals.csv"):
        assert f"wrote {tmp_path / f}" in res.output


def test_dnasim_steady_engineering_units(tmp_path):
    res = invoke(
        "steady", PLANTS / "steady_prv_station.toml", "--units", "engineering", "-o", tmp_path
    )
    assert res.exit_code == 0, res.output
    assert "p [bar]" in res.output and "T [°C]" in res.output and "m [t/h]" in res.output
    with open(tmp_path / "nodes.csv", newline="") as f:
        nodes = {r["name"]: r for r in csv.DictReader(f)}
    assert float(nodes["n_lp_out"]["p [bar]"]) == pytest.approx(12.0, rel=1e-9)  # the set point


def test_saturated_pi_without_anti_windup_is_at_rest_but_its_integral_winds(tmp_path):
    # the seed's plain PI (eqs. 10.13, anti_windup = false) saturated at rest: its
    # output is the limit, the plant is at rest, and the integral, which no equation
    # reads there, winds at dm_I/dt = KI e (kept, its rate solved: free_at_rest); the
    # note says so
    from test_faults import _attemperator_pi_file

    import dnasim

    plant = dnasim.load_plant(_attemperator_pi_file(tmp_path))
    plant.components["turbine"].params["p"] = 1000.0  # [Pa]: the spray would need z > 1
    plant.components["pi"].params["anti_windup"] = False
    system = plant.compile()
    rest = find_steady_state(system, 0.0)
    at = system.index
    assert rest.saturated == [("pi", "high")]
    KI, e = plant.components["pi"].params["KI"], rest.y[at["pi.e"]]
    assert rest.yp[at["pi.m_I"]] == pytest.approx(KI * e, rel=1e-12)  # dm_I/dt = KI e
    assert "without anti-windup its integral winds" in rest.notes[0]


# ------------------------------------------------------------------ drums without a state at rest
# A drum without level control has one state too many at rest: its pressure follows from
# the mass balance alone (every flow is a function of p; the level changes none), and the
# energy balance must close at that same pressure, which it does only if the heat input
# matches the flows exactly. The example plants below miss by a little, so they have no
# state at rest (their given start drifts); the start says so, with the miss.

DRUM_PLANT = ROOT / "plants" / "turbine_trip_safety_valve.toml"


def _number(msg, before, after):
    import re

    m = re.search(re.escape(before) + r"\s*([-+0-9.e]+)\s*" + re.escape(after), msg)
    assert m, (before, msg)
    return float(m.group(1))


def test_drum_without_level_control_names_its_heat_miss_by_the_hand_balance():
    # turbine_trip_safety_valve at t0: feed 50 kg/s at 1000 kJ/kg, 87.1 MW, steam through
    # the stop valve m = C sqrt(p - 60 bar) (the safety valve leaks 4.6e-5 kg/s: it
    # moves p by 6 Pa, h'' by 3e-2 J/kg). Mass: p* = 60 bar + (50/C)^2; energy at p*:
    # 87.1 MW + 50 (1000 kJ/kg - h''(p*)), h'' from CoolProp's IF97: -44.53 kW
    system = load(DRUM_PLANT).plant.compile()
    with pytest.raises(SteadyStateError) as info:
        find_steady_state(system, 0.0)
    msg = str(info.value)
    assert "drum.energy cannot close at rest" in msg, msg
    C = 0.02887
    p_star = 60e5 + (50.0 / C) ** 2
    miss = 87.1e6 + 50.0 * (1000e3 - PropsSI("H", "P", p_star, "Q", 1, WATER))
    energy = msg[msg.index("drum.energy cannot close at rest") :]
    kw = _number(energy, "the energy balance is", "kW short")
    # CoolProp's and dnasim's IF97 saturation lines: measured 4.6 W (1e-4); 1e-3
    assert abs(-kw * 1e3 / miss - 1) < 1e-3, (kw, miss)
    # the pressure where the mass balances, printed to 6 digits (5e-7): 1e-5
    p_msg = _number(energy, "every other balance closes (at drum.p =", "bar)")
    assert abs(p_msg * 1e5 / p_star - 1) < 1e-5, (p_msg, p_star)
    # holding M instead the energy balance closes, 87.1 MW + 50 kg/s 1000 kJ/kg =
    # m_s(p) h''(p), and the mass misses by 50 kg/s - m_s(p)
    from scipy.optimize import brentq

    def m_s(p):
        return C * np.sqrt(p - 60e5)

    p_m = brentq(lambda p: m_s(p) * PropsSI("H", "P", p, "Q", 1, WATER) - 137.1e6, 85e5, 95e5)
    mass = msg[msg.index("drum.mass cannot close at rest") :]
    kg_s = _number(mass, "the mass balance is", "kg/s over")
    # the same saturation lines (4.6 W of 137 MW in m_s h''), C to 4 digits: 1e-3
    assert abs(kg_s / (50.0 - m_s(p_m)) - 1) < 1e-3, (kg_s, 50.0 - m_s(p_m))
    p_msg = _number(mass, "every other balance closes (at drum.p =", "bar)")
    assert abs(p_msg * 1e5 / p_m - 1) < 1e-5, (p_msg, p_m)


def test_drum_without_level_control_given_start_drifts_at_the_rate_of_its_heat_miss():
    # the given start run from -6000 s to 0 (the plant's time functions are constant
    # before 0): no rest, the level rises at a constant rate. Quasi-steady drift at a
    # pressure p = p* + delta held constant: the drum's (dM/dt, dU/dt) lie along the
    # level, (rho_l - rho_v, rho_l u_l - rho_v u_v) dV_l/dt, so
    #   Q_miss - (m_s' h'' + m dh''/dp) delta = -h* m_s' delta,
    #   h* = (rho_l u_l - rho_v u_v) / (rho_l - rho_v),  m_s' = dm_s/dp = m / (2 (p - 60 bar)),
    #   dV_l/dt = -m_s' delta / (rho_l - rho_v),
    # with Q_miss the start's heat miss (the test above: the hand value)
    system = load(DRUM_PLANT).plant.compile()
    res = simulate(
        system,
        t0=-6000.0,
        t_end=0.0,
        start="given",
        rtol=1e-8,
        atol_scaled=1e-8,
        t_eval=[-6000.0, -4000.0, -2000.0, 0.0],
    )
    assert res.success, res.message
    V = np.asarray(res["drum.V_l"])
    p = np.asarray(res["drum.p"])
    rates = np.diff(V[1:]) / 2000.0
    # after the first 2000 s the pressure has settled (1e-6 relative)
    assert abs(p[-1] / p[1] - 1) < 1e-6, p
    C, m = 0.02887, 50.0
    p_star = 60e5 + (m / C) ** 2
    h_v = PropsSI("H", "P", p_star, "Q", 1, WATER)
    miss = 87.1e6 + m * (1000e3 - h_v)
    rl, rv = (PropsSI("D", "P", p_star, "Q", q, WATER) for q in (0, 1))
    ul, uv = (PropsSI("U", "P", p_star, "Q", q, WATER) for q in (0, 1))
    h_star = (rl * ul - rv * uv) / (rl - rv)
    dhv = (
        PropsSI("H", "P", p_star + 1e3, "Q", 1, WATER)
        - PropsSI("H", "P", p_star - 1e3, "Q", 1, WATER)
    ) / 2e3
    ms = m / (2.0 * (p_star - 60e5))
    delta = miss / (ms * (h_v - h_star) + m * dhv)
    rate = -ms * delta / (rl - rv)
    print(f"dV_l/dt: run {rates}, closed form {rate:.6g} m3/s")
    # the linearisation in delta (4e-4 of p; measured 2.1e-4 in the rate): 2e-3
    assert np.all(np.abs(rates / rate - 1) < 2e-3), (rates, rate)
    assert abs(p[-1] - (p_star + delta)) < 1e-2 * abs(delta), (p[-1], p_star + delta)


def test_feed_pump_drum_without_level_control_has_no_state_at_rest():
    # tests/field/feedpump_closed_valve.toml at t0 (the feed valve 45 % open, 100 MW):
    # the feed and steam flows balance near 100 bar, where the heat is ~0.65 MW more
    # than the steam carries away; its given start's drum pressure rises until the drum
    # runs dry (the field test uses only the first 120 s)
    path = ROOT / "tests" / "field" / "feedpump_closed_valve.toml"
    system = load(path).plant.compile()
    with pytest.raises(SteadyStateError) as info:
        find_steady_state(system, 0.0)
    msg = str(info.value)
    assert "drum.energy cannot close at rest" in msg and "kW over" in msg, msg
    res = simulate(
        system, t0=-400.0, t_end=0.0, start="given", rtol=1e-8, atol_scaled=1e-8,
        t_eval=[-400.0, -300.0, -200.0, -100.0, 0.0],
    )  # fmt: skip
    assert res.success, res.message
    assert np.all(np.diff(np.asarray(res["drum.p"])) > 0)  # more heat in than out


DEADHEAD = """
[plant]
name = "feedpump_deadhead"
medium = "Water"

[simulation]
t_end = "10 s"
start = "steady"

[components.deaerator]
type = "PressureBoundary"
p = "5 bar"
T = "120 degC"
m_nominal = "50 kg/s"
ports = { port = "n_suction" }

[components.pump]
type = "Pump"
H0 = "1400 m"
H_nominal = "1150 m"
Q_nominal = "0.055 m3/s"
eta = 0.78
speed = 1.0
m_nominal = "50 kg/s"
ports = { inlet = "n_suction", outlet = "n_discharge" }

[components.feed_valve]
type = "ControlValve"
Kv = 90
opening = 0
m_nominal = "50 kg/s"
ports = { inlet = "n_discharge", outlet = "n_feed" }

[components.drum]
type = "PressureBoundary"
p = "104 bar"
T = "300 degC"
m_nominal = "50 kg/s"
ports = { port = "n_feed" }
"""


def test_pump_against_a_shut_valve_starts_at_its_shut_off_head(tmp_path):
    # feedpump_closed_valve's pump and shut feed valve with the drum as a boundary at
    # 104 bar: at rest the discharge node takes the shut-off head, p = p_DA + rho_DA g H0
    # (its header's 134.5 bar), the valve's leakage runs forward and the stagnant node
    # keeps the pump's delivery state h_DA + dp/(rho eta), not the drum's water
    system = loads(DEADHEAD, "deadhead.toml").plant.compile()
    rest = find_steady_state(system, 0.0)
    at = system.index
    rho = PropsSI("D", "P", 5e5, "T", 120 + 273.15, WATER)
    h_da = PropsSI("H", "P", 5e5, "T", 120 + 273.15, WATER)
    p_hand = 5e5 + rho * 9.80665 * 1400.0
    p = rest.y[system.node_index["n_discharge"]]
    # H = H0 + b Q sqrt(Q^2 + Q_reg^2) at the leakage flow, a few 1e-6 m of 1400 m
    # (measured 4.3e-9 in all); CoolProp's forward IF97 rho: 1e-12; 1e-7
    assert abs(p / p_hand - 1) < 1e-7, (p, p_hand)
    assert rest.y[at["feed_valve.m"]] > 0.0
    h = rest.y[system.node_index["n_discharge"] + 1]
    h_deliv = h_da + (p - 5e5) / (rho * 0.78)
    h_feed = PropsSI("H", "P", 104e5, "T", 300 + 273.15, WATER)
    # the shut valve's zero-flow exchange is 2.3e-3 of the pump's (field_checks)
    assert abs(h - h_deliv) <= 2.3e-3 * abs(h_feed - h_deliv) + 1e-6 * h_deliv, (h, h_deliv)
    path = tmp_path / "deadhead.toml"
    path.write_text(DEADHEAD)
    out = invoke("steady", path)
    assert out.exit_code == 0, out.output
    line = next(r for r in out.output.splitlines() if r.startswith("n_discharge"))
    assert line.split()[1] == f"{p_hand:.6g}", line  # 1.34503e+07 Pa
