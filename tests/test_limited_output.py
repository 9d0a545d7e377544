"""The limited output, written once (issue 21): ``dnasim.library.submodels.limited_output``
is the modes, output residual and switch functions of the PI and PID controllers'
output limits and of the Limiter and RateLimiter blocks."""

from pathlib import Path

import pytest

from dnasim.library import controller, pid, signal_blocks
from dnasim.library.submodels.limited_output import LIMITED, RATE_LIMITED, LimitedOutput


def test_modes_target_and_start():
    modes = {}
    assert LIMITED.mode(modes) == "free"
    # the output equals the demand, or the limit it is held at
    assert LIMITED.target("free", 0.3, 0.0, 1.0) == 0.3
    assert LIMITED.target("high", 1.3, 0.0, 1.0) == 1.0
    assert LIMITED.target("low", -0.3, 0.0, 1.0) == 0.0
    # the start's mode: beyond a limit by more than tol
    assert LIMITED.start(modes, 1.5, 0.0, 1.0) and modes["mode"] == "high"
    assert not LIMITED.start(modes, 1.5, 0.0, 1.0)  # unchanged: False
    assert LIMITED.mode_at(1.0 + 1e-13, 0.0, 1.0, tol=1e-12) == "free"
    assert LIMITED.mode_at(-1e-11, 0.0, 1.0, tol=1e-12) == "low"
    LIMITED.reset(modes)
    assert modes == {"mode": "free"}


def test_switch_functions_are_positive_while_the_mode_holds():
    hi, lo = 1.0, 0.0
    # free inside the limits: both positive; they cross zero at the limits
    assert LIMITED.upper(0.5, hi, "free") == 0.5 and LIMITED.lower(0.5, lo, "free") == 0.5
    assert LIMITED.upper(1.2, hi, "free") < 0 and LIMITED.lower(-0.2, lo, "free") < 0
    # saturated: positive while the demand stays beyond its limit
    assert LIMITED.upper(1.2, hi, "high") == pytest.approx(0.2, rel=1e-12)
    assert LIMITED.upper(0.9, hi, "high") < 0
    assert LIMITED.lower(-0.2, lo, "low") == 0.2 and LIMITED.lower(0.1, lo, "low") < 0
    modes = {}
    assert LIMITED.toggle(modes, "high") == "free" and modes["mode"] == "high"
    assert LIMITED.toggle(modes, "high") == "high" and modes["mode"] == "free"
    rate = LimitedOutput("up", "down")
    assert rate.mode_at(5.0, -1.0, 2.0) == "up" and rate.mode_at(-5.0, -1.0, 2.0) == "down"


def test_one_implementation_for_the_controllers_and_the_limiters():
    assert controller.LIMITED is pid.LIMITED is signal_blocks.LIMITED is LIMITED
    assert signal_blocks.RateLimiter.LIMITS is RATE_LIMITED
    assert signal_blocks.Limiter.LIMITS is LIMITED
    # no module keeps its own copy of the mode logic: the modes are written by the
    # helper only
    for mod in (controller, pid, signal_blocks):
        text = Path(mod.__file__).read_text()
        assert 'modes["mode"] =' not in text, mod.__name__
        assert 'x.modes["mode"]' not in text, mod.__name__
