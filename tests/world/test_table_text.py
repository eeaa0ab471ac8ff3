"""``--table`` text: units, the plausible sizes of a dining table, and round trips."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from llm_grop.errors import BadInput
from llm_grop.world.table import MAX_TABLE_SIDE_M, MIN_TABLE_SIDE_M, Table


@pytest.mark.parametrize("text, table", [
    ("120x80cm", Table(1.2, 0.8)),
    ("1.2x0.8m", Table(1.2, 0.8)),
    ("1200x800mm", Table(1.2, 0.8)),
    ("120 cm x 80 cm", Table(1.2, 0.8)),
    ("1.2mx80cm", Table(1.2, 0.8)),
    ("90X60CM", Table(0.9, 0.6)),
    ("round:120cm", Table.circle(1.2)),
    ("round:1.2m", Table.circle(1.2)),
    ("ROUND: 1500 mm", Table.circle(1.5)),
    # A bare number is metres, as before units were read.
    ("0.9x0.6", Table(0.9, 0.6)),
    ("round:1.2", Table.circle(1.2)),
])
def test_sizes_with_units_are_metres(text: str, table: Table) -> None:
    assert Table.parse(text) == table


@pytest.mark.parametrize("text, words", [
    ("120x80", "table: 120 x 80 m is not a dining table (each side between 0.3 and 10 m); "
               "did you mean 120x80cm?"),
    ("1200x800", "table: 1200 x 800 m is not a dining table (each side between 0.3 and "
                 "10 m); did you mean 1200x800mm?"),
    ("1.2x0.8cm", "table: 0.012 x 0.008 m is not a dining table (each side between 0.3 "
                  "and 10 m); did you mean 1.2x0.8m?"),
    ("round:120", "table: round 120 m is not a dining table (diameter between 0.3 and "
                  "10 m); did you mean round:120cm?"),
    ("1000000000x1000000000", "table: 1e+09 x 1e+09 m is not a dining table (each side "
                              "between 0.3 and 10 m)"),
    ("0.2x0.2", "table: 0.2 x 0.2 m is not a dining table (each side between 0.3 and 10 m)"),
    ("0.9x20", "table: 0.9 x 20 m is not a dining table"),
])
def test_implausible_sizes_are_refused_with_a_hint(text: str, words: str) -> None:
    with pytest.raises(BadInput) as err:
        Table.parse(text)
    message = str(err.value)
    assert message.startswith(words) and "\n" not in message
    if text.startswith("1000000000"):
        assert "did you mean" not in message  # no unit makes that a table


@pytest.mark.parametrize("text, words", [
    ("0x0.6", "table: size must be positive"),
    ("round:0cm", "table: size must be positive"),
    ("-1x0.6", "expected WxD"),
    ("0.9x-0.6", "expected WxD"),
    ("nanx0.6", "expected WxD"),
    ("infxinf", "expected WxD"),
    ("round:nan", "round:D such as round:1.2"),
    ("round:-1.2", "round:D such as round:1.2"),
    ("1e3x1e3", "expected WxD"),
    ("120x80km", "expected WxD"),
    ("120cmx80", "table: 120cmx80 gives a unit for the first side only; write 120x80cm"),
    ("9" * 400 + "x1", "table: size must be positive and finite"),
])
def test_nan_inf_negative_zero_and_garbage_are_one_line_bad_input(text: str,
                                                                   words: str) -> None:
    with pytest.raises(BadInput, match="^table: ") as err:
        Table.parse(text)
    assert words in str(err.value) and "\n" not in str(err.value)
    assert "a unit may follow" in str(err.value) or "expected" not in str(err.value)


def test_the_table_refuses_a_size_that_is_not_finite() -> None:
    for w, d in ((math.inf, 0.6), (0.9, math.nan), (-0.9, 0.6)):
        with pytest.raises(BadInput, match="size must be positive and finite"):
            Table(w, d)


def test_the_bounds_are_inclusive() -> None:
    assert Table.parse(f"{MIN_TABLE_SIDE_M}x{MAX_TABLE_SIDE_M}").size == (MIN_TABLE_SIDE_M,
                                                                        MAX_TABLE_SIDE_M)
    assert Table.parse("30x1000cm") == Table(0.3, 10.0)


_SIDE_MM = st.integers(int(MIN_TABLE_SIDE_M * 1000), int(MAX_TABLE_SIDE_M * 1000))


@given(_SIDE_MM, _SIDE_MM, st.booleans(), st.sampled_from(["mm", "cm", "m", ""]))
def test_text_round_trips_through_parse(w_mm: int, d_mm: int, round_top: bool,
                                        unit: str) -> None:
    scale = {"mm": 1, "cm": 10, "m": 1000, "": 1000}[unit]
    w, d = w_mm / scale, d_mm / scale
    text = f"round:{w}{unit}" if round_top else f"{w}x{d}{unit}"
    table = Table.parse(text)
    assert Table.parse(table.text) == table
    assert table.width == pytest.approx(w_mm / 1000, abs=1e-12)
    if not round_top:
        assert table.depth == pytest.approx(d_mm / 1000, abs=1e-12)
