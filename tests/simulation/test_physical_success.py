"""Success is a physical state: it holds exactly when every requested object rests upright
on its intended support, within tolerance of its target, in 2D and in MuJoCo."""

from __future__ import annotations

import math
from collections.abc import Sequence

import mujoco
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from llm_grop import seeds
from llm_grop.api import run
from llm_grop.execution import ExecutionPolicy, execute, execute_plan
from llm_grop.simulation.kinematic2d import Kinematic2D, Kinematic2DOptions
from llm_grop.simulation.mujoco.session import MujocoSession
from llm_grop.simulation.mujoco.simulator import MujocoOptions, MujocoSimulator
from llm_grop.world.catalog import Catalog
from llm_grop.world.plan import ExecutedStep, ObjectState
from llm_grop.world.request import items_from_names
from llm_grop.world.scene import ObjectSource
from scenes import Constant, two_table_room
from simulation.test_mujoco import _item, _plan
from simulation.test_simulator_contract import check_execution, tiny_plan


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), nav=st.floats(0.3, 1.0), manip=st.floats(0.2, 1.0),
       attempts=st.integers(1, 4))
def test_2d_success_is_physical(seed: int, nav: float, manip: float, attempts: int) -> None:
    scene, plan, navigator = tiny_plan()
    items = items_from_names(list(plan.order), Catalog.load())
    sim = Kinematic2D(Kinematic2DOptions(outcomes=Constant(nav, manip)))
    policy = ExecutionPolicy(manip_attempts=attempts, nav_attempts=attempts)
    ex = execute(sim, plan, scene, items, np.random.default_rng(seed), replan=navigator,
                 policy=policy)
    check_execution(ex, plan, scene, policy)


def test_task8_grop_seed11_mug_on_its_side_is_no_success() -> None:
    """The episode that once reported success with the mug lying on its side."""
    for seed in (11, 0):
        result = run(task=8, method="grop", seed=seed, simulator="mujoco")
        check_execution(result.execution, result.plan, result.scene)
        for p in result.final.placements:
            if p.tilt_rad > ExecutionPolicy().max_tilt_rad:
                assert not result.success and p.name in result.execution.unplaced


class Tipping:
    """A MuJoCo session whose first place of ``name`` is knocked onto its side once the
    hand has let go: the test hook that makes a placed object tip."""

    def __init__(self, inner: MujocoSession, name: str) -> None:
        self.inner, self.name, self.tipped = inner, name, False

    def __getattr__(self, attr: str) -> object:
        return getattr(self.inner, attr)

    @property
    def time_s(self) -> float:
        return self.inner.time_s

    @property
    def held(self) -> str | None:
        return self.inner.held

    def place(self, name: str, x: float, y: float, yaw: float, on: str | None = None
              ) -> ExecutedStep:
        done = self.inner.place(name, x, y, yaw, on)
        if done.ok and name == self.name and not self.tipped:
            self.tipped = True
            w = self.inner.w
            joint = w.m.body(name).jntadr[0]
            adr = w.m.jnt_qposadr[joint]
            w.d.qpos[adr + 2] += 0.05
            # A quarter turn about x: the mug lies on its side.
            w.d.qpos[adr + 3:adr + 7] = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0, 0)
            mujoco.mj_forward(w.m, w.d)
            w.advance(1.0)
        return done

    def objects(self) -> dict[str, ObjectState]:
        return self.inner.objects()

    def navigate(self, *args: object) -> ExecutedStep:
        return self.inner.navigate(*args)  # type: ignore[arg-type]

    def pick(self, name: str) -> ExecutedStep:
        return self.inner.pick(name)

    def release(self, name: str) -> float:
        return self.inner.release(name)

    def close(self) -> None:
        self.inner.close()


def test_a_mug_knocked_over_after_release_is_tipped_and_unplaced() -> None:
    scene = two_table_room(sources=(ObjectSource("mug", "counter", 0.45, 1.8),
                                    ObjectSource("dinner plate", "counter", 0.45, 2.2)))
    plan, nav = _plan(scene, _item("dinner plate", -0.15, 0.0), _item("mug", 0.2, 0.0))
    items: Sequence = items_from_names(list(plan.order), Catalog.load())
    session = MujocoSimulator(MujocoOptions(nav_noise_var_m2=0.0)).session(
        scene, items, seeds.stream(0, "simulator"), replan=nav)
    ex = execute_plan(plan, Tipping(session, "mug"), scene)  # type: ignore[arg-type]
    check_execution(ex, plan, scene)
    places = [s for s in ex.steps if s.action == "place" and s.object == "mug"]
    assert places[0].reason == "tipped" and not places[0].ok
    assert "tipped over" in places[0].note
    assert dict(ex.unplaced_reasons) == {"mug": "tipped"} and not ex.success
    mug = {p.name: p for p in ex.final}.get("mug")
    assert mug is None or mug.tilt_rad > 1.0


def test_2d_tipped_place_is_reported_with_its_reason() -> None:
    scene, plan, navigator = tiny_plan()
    items = items_from_names(list(plan.order), Catalog.load())
    sim = Kinematic2D(Kinematic2DOptions(outcomes=Constant(1.0, 0.6),
                                         place_failures=(("tipped", 1.0),)))
    tipped = 0
    for seed in range(20):
        ex = execute(sim, plan, scene, items, np.random.default_rng(seed), replan=navigator)
        check_execution(ex, plan, scene)
        for s in ex.steps:
            if s.reason == "tipped":
                tipped += 1
                assert dict(ex.unplaced_reasons)[s.object or ""] == "tipped"
                assert not ex.success
                assert {p.name: p for p in ex.final}[s.object or ""].tilt_rad > 1.0
    assert tipped > 0
