"""The executive alone, over a scripted session: the same outcomes of the primitives give
the same policy path, whichever simulator would have produced them."""

from __future__ import annotations

import math
from typing import Any

import pytest

from llm_grop.errors import BadInput
from llm_grop.execution import ExecutionPolicy, execute_plan
from llm_grop.execution.judge import CLEAR_GAP_M, clear_of
from llm_grop.planning.grop import build_plan, choose
from llm_grop.planning.navigation import Navigator
from llm_grop.planning.utility import PlanningContext
from llm_grop.world.arrangement import Placement
from llm_grop.world.catalog import Catalog
from llm_grop.world.plan import Execution, Plan, Step
from llm_grop.world.request import items_from_names
from llm_grop.world.scene import Scene
from scenes import config, placement, two_table_room
from scripted_session import SECONDS, ScriptedSession

FLAT = (placement("dinner plate", 0.0, -0.05),
        placement("dinner fork", -0.22, -0.05, "box", (0.025, 0.2)),
        placement("dinner knife", 0.22, -0.05, "box", (0.025, 0.2)))
STACK = (placement("dinner plate", 0.0, -0.05),
         placement("bread", 0.0, -0.05, "box", (0.1, 0.08), on="dinner plate"))


def plan_for(*placements: Placement) -> tuple[Scene, Plan]:
    scene = two_table_room()
    ctx = PlanningContext(scene, items_from_names([p.name for p in placements],
                                                  Catalog.load()))
    nav = Navigator(scene, scene.robot.base_radius_m)
    return scene, build_plan(ctx, choose(ctx, [config(*placements)]), nav, seed=0,
                             configurations=1)


def run(placements: tuple[Placement, ...], script: dict[str, list[str]] | None = None,
        hooks: dict[int, Any] | None = None, **policy: Any
        ) -> tuple[Execution, ScriptedSession, Plan]:
    scene, plan = plan_for(*placements)
    session = ScriptedSession(scene, plan.order, script or {}, hooks or {})
    ex = execute_plan(plan, session, scene, ExecutionPolicy(**policy))
    return ex, session, plan


def legs(plan: Plan, name: str) -> list[Step]:
    return [s for s in plan.steps if s.action == "navigate" and s.object == name]


def test_every_primitive_succeeding_follows_the_plan_once() -> None:
    ex, session, plan = run(FLAT)
    assert [a for a, _ in session.calls] == [s.action for s in plan.steps]
    # Only the first attempt at a planned goal follows the plan's path.
    assert all(w.endswith(" path") for a, w in session.calls if a == "navigate")
    assert ex.success and ex.failures == 0 and ex.unplaced_reasons == ()
    assert [p.name for p in ex.final] == [p.name for p in plan.configuration]
    assert all(p.tilt_rad == 0.0 and p.z_m == 0.0 for p in ex.final)
    assert ex.execution_time_s == pytest.approx(session.time_s) and session.closed


def test_navigation_is_retried_then_falls_back_to_the_next_goal() -> None:
    scene, plan = plan_for(*FLAT)
    leg = legs(plan, plan.order[0])[1]
    assert leg.alternatives, "the place leg has fallback standing positions"
    ex, session, _ = run(FLAT, {"navigate": ["ok", "contact", "contact", "contact", "ok"]})
    navs = [s for s in ex.steps if s.action == "navigate"][:5]
    assert [(s.ok, s.attempt, s.reason) for s in navs] == [
        (True, 1, None), (False, 1, "contact"), (False, 2, "contact"), (False, 3, "contact"),
        (True, 1, None)]
    assert navs[4].goal == leg.alternatives[0]
    # Attempts after the first plan their own path.
    assert [w.endswith(" path") for a, w in session.calls if a == "navigate"][:5] == [
        True, True, False, False, False]
    assert ex.success


def test_no_path_skips_to_the_next_goal_at_once() -> None:
    ex, _, plan = run(FLAT, {"navigate": ["ok", "blocked", "ok"]})
    navs = [s for s in ex.steps if s.action == "navigate"]
    assert navs[1].reason == "blocked" and navs[2].goal == legs(plan, plan.order[0])[1] \
        .alternatives[0]
    assert ex.success


def test_an_unreachable_place_moves_to_the_next_standing_position() -> None:
    ex, session, plan = run(FLAT, {"place": ["no_ik", "ok"]})
    first = plan.order[0]
    assert [a for a, _ in session.calls[:6]] == ["navigate", "pick", "navigate", "place",
                                                 "navigate", "place"]
    failed = ex.steps[3]
    assert failed.reason == "no_ik" and failed.duration_s == SECONDS["no_ik"]
    assert ex.steps[4].goal == legs(plan, first)[1].alternatives[0]
    assert ex.steps[5].ok and ex.steps[5].attempt == 2 and ex.success


def test_an_object_that_slid_is_regrasped_and_placed_again() -> None:
    ex, session, plan = run(FLAT, {"place": ["slid", "ok"]})
    first = plan.order[0]
    assert session.calls[3:6] == [("place", first), ("pick", first), ("place", first)]
    slid = ex.steps[3]
    assert not slid.ok and slid.reason == "slid" and "5.0 cm from its target" in slid.note
    assert ex.steps[4].action == "pick" and ex.steps[4].attempt == 2
    assert ex.steps[5].ok and ex.steps[5].attempt == 2
    assert ex.success


def test_a_place_that_fails_the_same_way_twice_is_not_tried_a_third_time() -> None:
    # Both attempts leave the object 5 cm off its target, at the same spot.
    ex, session, plan = run(FLAT, {"place": ["slid", "slid", "ok"]})
    first = plan.order[0]
    assert [w for a, w in session.calls if a == "place"].count(first) == 2
    assert dict(ex.unplaced_reasons)[first] == "slid"
    assert ex.unplaced == (first,)  # the others are placed


def test_an_attempt_that_never_left_the_hand_breaks_a_repeat() -> None:
    # Slid, then beyond reach (moved to another standing position), then slid to the
    # same spot: not twice in a row, so it is tried again.
    ex, session, plan = run(FLAT, {"place": ["slid", "no_ik", "slid", "ok"]})
    first = plan.order[0]
    assert [w for a, w in session.calls if a == "place"].count(first) == 4
    assert ex.success


def test_an_object_dropped_in_transit_is_given_up_without_more_drives() -> None:
    # The second drive carries the first object to the table; it slips out on the way.
    ex, session, plan = run(FLAT, {"navigate": ["ok", "dropped"]})
    first = plan.order[0]
    dropped = ex.steps[2]
    assert dropped.action == "navigate" and dropped.reason == "fell"
    # No retry of that drive, no place: the object is on the floor, given up.
    assert session.calls[3][0] == "navigate" and session.calls[3][1] != session.calls[2][1]
    assert ("place", first) not in session.calls
    assert dict(ex.unplaced_reasons)[first] == "fell"
    assert not ex.success
    assert {p.name for p in ex.final} == set(plan.order) - {first}


def test_an_object_dropped_on_the_way_to_the_next_standing_position_is_given_up() -> None:
    # The first place is out of reach; driving to the next standing position, the object
    # slips from the hand. The executive gives it up rather than place an empty hand.
    ex, session, plan = run(FLAT, {"place": ["no_ik"], "navigate": ["ok", "ok", "dropped"]})
    first = plan.order[0]
    assert [s.reason for s in ex.steps[3:5]] == ["no_ik", "fell"]
    assert session.calls.count(("place", first)) == 1
    assert dict(ex.unplaced_reasons)[first] == "fell"


@pytest.mark.parametrize("outcome", ["tipped", "fell"])
def test_a_tipped_or_fallen_object_is_unplaced_and_the_run_fails(outcome: str) -> None:
    ex, session, plan = run(STACK, {"place": [outcome]})
    assert plan.order[0] == "dinner plate"
    assert ex.steps[3].reason == outcome and not ex.steps[3].ok
    assert ("release", "dinner plate") not in session.calls  # it already left the hand
    reasons = dict(ex.unplaced_reasons)
    assert reasons["dinner plate"] == outcome
    # The bread goes on the table where its plate should be: not on its support.
    assert reasons["bread"] == "wrong_support"
    assert not ex.success
    final = {p.name: p for p in ex.final}
    if outcome == "tipped":
        assert final["dinner plate"].tilt_rad == pytest.approx(1.5708, abs=1e-3)
    else:
        assert "dinner plate" not in final


def test_a_disturbed_object_is_reported_and_placed_again() -> None:
    scene, plan = plan_for(*FLAT)
    first, last = plan.order[0], plan.order[-1]
    # Push the first object 6 cm while the last one is put down.
    index = [s.action for s in plan.steps].index("place", len(plan.steps) - 1)
    ex, session, _ = run(FLAT, hooks={index: lambda s: s.move(first, 0.06)})
    report = next(s for s in ex.steps if s.reason == "disturbed")
    assert report.object == first and report.action == "place" and not report.ok
    assert repr(last) in report.note and report.duration_s == 0.0
    assert session.calls[-3:] == [("navigate", session.calls[-3][1]), ("pick", first),
                                  ("place", first)]
    assert ex.success


def test_a_disturbed_object_that_carries_another_is_left_and_reported() -> None:
    scene, plan = plan_for(*STACK)
    ex, _, _ = run(STACK, hooks={len(plan.steps) - 1: lambda s: (
        s.move("dinner plate", 0.06), s.move("bread", 0.06))})
    assert dict(ex.unplaced_reasons)["dinner plate"] == "disturbed"
    assert not ex.success


def test_giving_up_puts_the_object_down_and_keeps_every_second() -> None:
    ex, session, plan = run(FLAT, {"place": ["contact"] * 10})
    first = plan.order[0]
    places = [s for s in ex.steps if s.action == "place" and s.object == first]
    assert len(places) == 10 and {s.reason for s in places} == {"contact"}
    assert ("release", first) in session.calls
    assert dict(ex.unplaced_reasons) == {first: "contact"}
    assert ex.execution_time_s == pytest.approx(session.time_s)
    # The rest of the plan goes on.
    assert set(ex.unplaced) == {first} and len(ex.final) == len(FLAT) - 1


@pytest.mark.parametrize(("policy", "attempts"), [
    ({}, 10), ({"manip_attempts": 4}, 4)])
def test_attempt_counts(policy: dict[str, int], attempts: int) -> None:
    ex, _, plan = run(FLAT, {"pick": ["grasp_missed"] * 30}, **policy)
    picks = [s for s in ex.steps if s.action == "pick" and s.object == plan.order[0]]
    assert len(picks) == attempts


def test_the_method_fills_in_only_a_count_left_open() -> None:
    assert ExecutionPolicy().for_method(20).manip_attempts == 20
    assert ExecutionPolicy(manip_attempts=3).for_method(20).manip_attempts == 3


@pytest.mark.parametrize(("field", "value"), [
    ("nav_attempts", 0), ("manip_attempts", -1), ("max_tilt_rad", -0.1),
    ("max_offset_m", float("nan"))])
def test_bad_policy_is_bad_input(field: str, value: float) -> None:
    with pytest.raises(BadInput, match=field):
        ExecutionPolicy(**{field: value})  # type: ignore[arg-type]


@pytest.mark.parametrize(("field", "value"), [
    ("nav_attempts", True), ("max_offset_m", float("inf")), ("max_tilt_rad", "0.3")])
def test_policy_values_of_the_wrong_kind_are_bad_input(field: str, value: object) -> None:
    with pytest.raises(BadInput, match=field):
        ExecutionPolicy(**{field: value})  # type: ignore[arg-type]


def test_a_given_up_object_is_put_down_off_the_table_and_its_time_kept() -> None:
    """The release's seconds go to the object given up, not to another's report."""
    scene, plan = plan_for(*FLAT)
    first, second = plan.order[0], plan.order[1]
    index = [k for k, s in enumerate(plan.steps) if s.action == "place"][1]
    hooks = {index + 1: lambda s: s.move(first, 0.06)}
    ex, session, _ = run(FLAT, {"place": ["ok", "contact", "contact"]}, hooks,
                         manip_attempts=2)
    assert dict(ex.unplaced_reasons).get(second) == "contact"
    released = [s for s in ex.steps if s.object == second][-1]
    assert released.duration_s == SECONDS["place"] + SECONDS["release"]
    assert all(s.duration_s == 0.0 for s in ex.steps if s.reason == "disturbed")
    assert ex.execution_time_s == pytest.approx(session.time_s)


def test_a_disturbed_object_is_put_back_even_when_the_one_that_moved_it_is_given_up() -> None:
    scene, plan = plan_for(*FLAT)
    first, last = plan.order[0], plan.order[-1]
    pick = [k for k, s in enumerate(plan.steps) if s.action == "pick"][-1]
    ex, session, _ = run(FLAT, {"pick": ["ok", "ok", "grasp_missed"] + ["grasp_missed"] * 9},
                         hooks={pick: lambda s: s.move(first, 0.06)})
    assert dict(ex.unplaced_reasons) == {last: "grasp_missed"}
    assert session.calls[-2:] == [("pick", first), ("place", first)]


def test_the_last_unreachable_attempt_does_not_drive_anywhere() -> None:
    ex, session, plan = run(FLAT, {"place": ["no_ik"] * 50}, manip_attempts=3)
    first = plan.order[0]
    k = session.calls.index(("place", first))
    tail = session.calls[k:session.calls.index(("release", first))]
    assert [a for a, _ in tail] == ["place", "navigate", "place", "navigate", "place"]


def test_an_object_knocked_over_is_not_picked_again() -> None:
    scene, plan = plan_for(*FLAT)
    first = plan.order[0]
    pick = [s.action for s in plan.steps].index("pick")
    ex, session, _ = run(FLAT, {"pick": ["grasp_missed"]},
                         hooks={pick: lambda s: s.move(first, 0.0, tilt_rad=1.5)})
    assert session.calls.count(("pick", first)) == 1
    assert dict(ex.unplaced_reasons)[first] == "tipped"


def test_an_object_that_goes_on_another_is_aimed_at_its_support_where_it_lies() -> None:
    scene, plan = plan_for(*STACK)
    index = [s.action for s in plan.steps].index("place")
    # The plate comes to rest 2 cm off its target, within tolerance.
    ex, session, _ = run(STACK, hooks={index: lambda s: s.move("dinner plate", 0.02)})
    states = session.objects()
    assert states["bread"].on == "dinner plate"
    assert (states["bread"].x, states["bread"].y) == pytest.approx(
        (states["dinner plate"].x, states["dinner plate"].y))
    assert ex.success and ex.failures == 0


def test_a_place_that_came_to_rest_on_another_object_aims_beside_it_next() -> None:
    close = (placement("dinner plate", 0.0, -0.05),
             placement("dinner knife", 0.16, -0.05, "box", (0.025, 0.2)))
    scene, plan = plan_for(*close)
    first, second = plan.order
    targets = {p.name: scene.table_to_room(p.x, p.y) for p in close}
    toward = (targets[second].x - targets[first].x, targets[second].y - targets[first].y)
    step = 0.015 / math.hypot(*toward)
    index = [s.action for s in plan.steps].index("place")
    # The first object comes to rest 1.5 cm towards the second's spot (within tolerance),
    # and the second, put down at its target, lands on it.
    ex, session, _ = run(close, {"place": ["ok", f"on:{first}"]}, hooks={
        index: lambda s: s.move(first, step * toward[0], step * toward[1])})
    assert [w for a, w in session.calls if a == "place"] == [first, second, second]
    failed = next(s for s in ex.steps if s.action == "place" and not s.ok)
    assert failed.reason == "wrong_support" and failed.object == second
    states = session.objects()
    assert states[second].on is None and ex.success
    moved = math.hypot(states[second].x - targets[second].x,
                       states[second].y - targets[second].y)
    assert 0.0 < moved <= 0.8 * ExecutionPolicy().max_offset_m


def test_a_target_is_moved_clear_only_within_the_limit() -> None:
    lid = placement("mug lid", 0.0, 0.0, size=(0.095, 0.095))
    knife = placement("dinner knife", 0.055, 0.0, "box", (0.02, 0.23))
    x, y = clear_of(0.0, 0.0, lid, knife, 0.024)  # type: ignore[misc]
    assert y == 0.0 and -0.024 <= x < 0.0
    assert math.isclose(0.055 - 0.01 - (x + 0.0475), CLEAR_GAP_M, abs_tol=0.002)
    assert clear_of(0.0, 0.0, lid, knife, 0.005) is None
    assert clear_of(-0.2, 0.0, lid, knife, 0.024) == (-0.2, 0.0)  # already clear
