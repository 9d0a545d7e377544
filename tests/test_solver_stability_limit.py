"""Stability-limit detection: BDF4 held by its stability region drops to order 3.

The 1000-volume steam pipe (tests/field/long_pipe_step.toml) after its temperature
front: order 4 kept h at ~4 ms (3 times the 1.3 ms residence time of a volume) for
hundreds of steps with the error estimates of orders 3, 4 and 5 all of one size, where
order 3 takes 0.13 s steps (benchmarks/README.md, "Stability-limit detection").
"""

from pathlib import Path

import numpy as np
import pytest

from dnasim.plant.plantfile import load
from dnasim.solver import controller
from dnasim.solver.controller import StepController

ROOT = Path(__file__).resolve().parent.parent
TARGET = controller.ERROR_TARGET


def _controller(h=1e-3):
    c = StepController(max_order=5)
    c.restart(h)
    c.h = h  # the step size the detector is fed (``_feed``)
    return c


def _feed(c, q, estimates, steps, h_factor=1.0):
    """Call the detector `steps` times with (error, err_down, err_up); True once it fires."""
    fired = []
    for _ in range(steps):
        fired.append(c.stability_limited(q, c.h, *estimates))
        c.h *= h_factor
    return fired


def test_flat_estimates_at_a_held_step_fire_after_2_q_plus_1_steps():
    c = _controller()
    # e3, e4, e5 = 0.045, 0.030, 0.024 of the tolerance: the pipe's numbers
    fired = _feed(c, 4, (TARGET, 1.5 * TARGET, 0.8 * TARGET), 10)
    assert fired == [False] * 9 + [True]
    assert c.stability_h == {4: pytest.approx(1e-3)}


def test_estimates_falling_with_the_order_never_fire():
    # a resolved solution: each order's estimate a fraction h/tau of the lower one's
    c = _controller()
    assert not any(_feed(c, 4, (TARGET, 4.0 * TARGET, 0.3 * TARGET), 50))


def test_a_step_below_its_error_target_never_fires():
    # flat estimates, but the error is far below its target: the step is growing
    c = _controller()
    assert not any(_feed(c, 4, (0.1 * TARGET, 0.15 * TARGET, 0.1 * TARGET), 50))


def test_a_changing_step_size_never_fires():
    # flat estimates while h moves by 10 % a step (a resolved oscillation, the
    # transistor amplifier of the Test Set): no run of 2 (q + 1) steps at one h
    c = _controller()
    assert not any(_feed(c, 4, (TARGET, 1.5 * TARGET, 0.8 * TARGET), 50, h_factor=1.1))


def test_orders_below_four_are_left_alone():
    # BDF3's A(86 deg) wedge: dropping it to BDF2 cost the pipe steps (measured)
    c = _controller()
    assert not any(_feed(c, 3, (TARGET, 1.5 * TARGET, 0.8 * TARGET), 50))


def _pipe_run(monkeypatch, detect: bool):
    if not detect:
        monkeypatch.setattr(controller, "MIN_Q_STAB", 99)
    plant = load(ROOT / "tests" / "field" / "long_pipe_step.toml")
    res = plant.simulate()
    assert res.success, res.message
    return res


def test_the_1000_volume_pipe_takes_fewer_steps_with_the_same_answer(monkeypatch):
    """About 8 s of CPU (two runs of the 1000-volume pipe, 4 s simulated)."""
    held = _pipe_run(monkeypatch, detect=False)
    monkeypatch.undo()
    dropped = _pipe_run(monkeypatch, detect=True)
    n_held, n_dropped = held.stats["steps"], dropped.stats["steps"]
    # measured 735 and 355: from 1.9 s to 4 s, after the front, order 4 holds h at
    # ~4 ms where order 3 takes 0.13 s steps; 0.8 leaves room for rounding without
    # accepting no effect
    assert n_dropped < 0.8 * n_held
    Tw = [i for i, n in enumerate(dropped.names) if n.startswith("pipe.T_w")]
    # both are rtol = 1e-6 solutions: their wall temperatures (~793 K) differ from a
    # rtol = 1e-10 reference by 2e-3 to 3e-3 K at t = 61 s (benchmarks/README.md);
    # 1e-2 K bounds the difference of two such solutions with margin
    assert np.max(np.abs(dropped.y[Tw, -1] - held.y[Tw, -1])) < 1e-2
