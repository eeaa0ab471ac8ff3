"""The one angle wrap: into ``(-pi, pi]``, the same angle, the half turn as ``pi``."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from llm_grop.geometry.motion import wrap
from llm_grop.world.angles import TURN, wrap_angle

#: Angles as the callers make them: sums and differences of headings and yaws, and
#: controllers' errors, radians; huge ones too, where ``angle + pi`` loses digits.
angles = st.floats(min_value=-1e9, max_value=1e9, allow_nan=False, allow_infinity=False)
#: Whole turns, for adding to an angle.
turns = st.integers(min_value=-50, max_value=50)


@given(angles)
def test_the_result_is_in_the_half_open_range(angle: float) -> None:
    assert -math.pi < wrap_angle(angle) <= math.pi


@given(angles)
def test_the_result_is_the_same_angle(angle: float) -> None:
    # Off by whole turns, but for the rounding of angle + pi (and of the check's own
    # difference).
    tolerance = 2 * math.ulp(abs(angle) + TURN)
    assert abs(math.remainder(wrap_angle(angle) - angle, TURN)) <= tolerance


@given(st.floats(min_value=-math.pi, max_value=math.pi, exclude_min=True), turns)
def test_an_angle_and_that_angle_turned_whole_turns_wrap_alike(angle: float, k: int) -> None:
    # Alike as angles: by the half turn, pi and a hair above -pi are a hair apart.
    assert abs(math.remainder(wrap_angle(angle + k * TURN) - angle, TURN)) <= 1e-12


@given(angles)
def test_wrapping_twice_moves_by_rounding_at_most(angle: float) -> None:
    once = wrap_angle(angle)
    assert abs(wrap_angle(once) - once) <= math.ulp(math.pi)


@given(angles)
def test_only_the_half_turn_differs_from_the_planners_former_minus_pi_end(angle: float) -> None:
    # geometry/motion.py and env/dining.py wrapped into [-pi, pi) with this formula: the
    # result is the same but at the half turn, and its size (the turn a planner costs) is
    # the same always.
    former = (angle + math.pi) % TURN - math.pi
    assert wrap_angle(angle) == (math.pi if former == -math.pi else former)
    assert abs(wrap_angle(angle)) == abs(former)


@pytest.mark.parametrize("angle, wrapped", [
    (0.0, 0.0), (-0.0, 0.0), (math.pi, math.pi), (-math.pi, math.pi), (3 * math.pi, math.pi),
    (TURN, 0.0), (-TURN, 0.0), (math.pi / 2, math.pi / 2), (-math.pi / 2, -math.pi / 2),
    (math.pi / 2 + math.pi / 2, math.pi), (-math.pi / 2 - math.pi / 2, math.pi),
    (1.5 * math.pi, -math.pi / 2),
])
def test_wraps(angle: float, wrapped: float) -> None:
    assert wrap_angle(angle) == pytest.approx(wrapped, abs=1e-15)
    assert math.copysign(1.0, wrap_angle(angle)) == math.copysign(1.0, wrapped) or wrapped == 0


def test_the_former_name_is_the_one_wrap() -> None:
    assert wrap is wrap_angle


def test_an_infinite_angle_is_refused_and_nan_stays_nan() -> None:
    with pytest.raises(ValueError):
        wrap_angle(math.inf)
    assert math.isnan(wrap_angle(math.nan))
