"""The seed's two examples (Elmegaard, chapter 10.2) as plant builders.

``air_pipe_plant()``   10.2.2: hot air flows into a cold steel pipe.
``attemperator_plant()`` 10.2.3: steam temperature control with a PI controller
                        driving a spray-water valve; the controller saturates.
"""

from __future__ import annotations

import math

from dnasim.core.timefunctions import Ramp
from dnasim.library import Attemperator, PIController, Pipe, PressureBoundary, Valve
from dnasim.plant.plant import Plant


def air_pipe_plant(
    n_volumes: int = 1,
    *,
    T_in: float = 600.0,
    T_initial: float = 300.0,
    internal_energy: str | None = None,
) -> Plant:
    """Hot air entering a cold pipe (seed 10.2.2). Simulate with start="given".

    A steel pipe, 10 m long, inner diameter 0.1 m, wall 5 mm:
      V      = pi/4 0.1^2 10             = 0.0785 m3
      C_wall = 7850 kg/m3 * pi 0.105 0.005 10 m3 * 480 J/(kg K) = 6.2e4 J/K
      kA     = 50 W/(m2 K) * pi 0.1 10 m2 = 157 W/K
      k      = 1.2e5 1/m4 (about 10 mbar at 0.1 kg/s)
    Air (ideal gas, constant cp) from a 2 bar reservoir at T_in = 600 K flows
    through the pipe and a valve (C = 3.2e-4 kg/(s Pa^0.5)) into 1 bar; about
    0.1 kg/s. The pipe and the air in it start at T_initial = 300 K, 1.99 bar.
    With m cp ~ 100 W/K the NTU is about 1.6 and the wall's time constant
    C_wall / (m cp (1 - exp(-NTU))) is about 800 s: simulate ~4000 s.

    Nodes: inlet -> pipe1 -> outlet -> valve -> exhaust.
    """
    plant = Plant("air_pipe", medium="Air")
    L, D, s = 10.0, 0.1, 0.005
    plant.add(PressureBoundary("source", p=2.0e5, T=T_in))
    plant.add(
        Pipe(
            "pipe1",
            V=math.pi / 4 * D**2 * L,
            kA=50.0 * math.pi * D * L,
            k=1.2e5,
            C_wall=7850.0 * math.pi * (D + s) * s * L * 480.0,
            n_volumes=n_volumes,
            m_nominal=0.1,
            p0=1.99e5,
            T0=T_initial,
            T_wall0=T_initial,
            internal_energy=internal_energy,
        )
    )
    plant.add(Valve("valve", C=3.2e-4, opening=1.0, m_nominal=0.1))
    plant.add(PressureBoundary("exhaust", p=1.0e5, m_nominal=0.1))
    plant.connect("source.port", "inlet")
    plant.connect("pipe1.inlet", "inlet")
    plant.connect("pipe1.outlet", "outlet")
    plant.connect("valve.inlet", "outlet")
    plant.connect("valve.outlet", "exit")
    plant.connect("exhaust.port", "exit")
    return plant


def attemperator_plant(
    *,
    T_steam_high: float = 560.0 + 273.15,
    ramp=(10.0, 60.0),
    Kp: float = 0.01,
    KI: float = 5e-5,
    anti_windup: bool = False,
) -> Plant:
    """Steam temperature control (seed 10.2.3). Simulate with start="steady".

    Superheated steam (40 bar reservoir, 500 C, about 10 kg/s) flows through the
    attemperator (V = 0.5 m3, steam inlet friction k = 6500 1/m4) and a turbine
    valve (C = 0.0149 kg/(s Pa^0.5), fully open) into 35 bar. Spray water from a
    60 bar, 150 C reservoir enters through the spray valve
    (C = 4.9e-4 kg/(s Pa^0.5), at most about 0.7 kg/s), whose opening z is the
    output of a PI controller on the attemperator outlet temperature
    (set point 450 C, e = T_out - T_sp, Kp = 0.01 1/K, KI = 5e-5 1/(K s),
    output limited to [0, 1]).

    At t0 the plant is at steady state with the controller in range. The steam
    temperature then ramps from 500 C to T_steam_high (default 560 C) between
    ramp[0] and ramp[1] s; even a fully open spray valve cannot bring the outlet
    back to the set point, so the controller output rises to 1 and saturates
    there: the switch upper (z_max - (m_p + m_I)) crosses zero, near t = 227 s
    (the seed's Table 10.1 has 216.8 s). Simulate to 400 s.
    """
    plant = Plant("attemperation", medium="Water")
    plant.add(
        PressureBoundary(
            "steam", p=40e5, T=Ramp(ramp[0], ramp[1], 500.0 + 273.15, T_steam_high), m_nominal=10.0
        )
    )
    plant.add(PressureBoundary("water", p=60e5, T=150.0 + 273.15, m_nominal=0.5))
    plant.add(Attemperator("att", V=0.5, k=6500.0, m_nominal=10.0))
    plant.add(Valve("spray_valve", C=4.9e-4, m_nominal=0.5))
    plant.add(Valve("turbine_valve", C=0.0149, opening=1.0, m_nominal=10.0))
    plant.add(PressureBoundary("turbine", p=35e5, m_nominal=10.0))
    plant.add(
        PIController(
            "pi",
            Kp=Kp,
            KI=KI,
            setpoint=450.0 + 273.15,
            z_min=0.0,
            z_max=1.0,
            anti_windup=anti_windup,
            measured_nominal=700.0,
        )
    )
    plant.connect("steam.port", "steam_in")
    plant.connect("att.steam_in", "steam_in")
    plant.connect("water.port", "water_supply")
    plant.connect("spray_valve.inlet", "water_supply")
    plant.connect("spray_valve.outlet", "spray")
    plant.connect("att.water_in", "spray")
    plant.connect("att.outlet", "mixed")
    plant.connect("turbine_valve.inlet", "mixed")
    plant.connect("turbine_valve.outlet", "exhaust")
    plant.connect("turbine.port", "exhaust")
    plant.link("att.T_out", "pi.measured")
    plant.link("pi.z", "spray_valve.z")
    return plant
