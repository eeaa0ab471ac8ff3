"""Several diners: seats, places, one setting per diner in their own frame, and the rater
rating each setting."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from llm_grop import BackendOptions, arrange
from llm_grop.arrangement.diners import seat_table
from llm_grop.arrangement.fidelity import GAP_TOLERANCE_M
from llm_grop.arrangement.pipeline import ArrangeOptions
from llm_grop.contract.serialize import arrangement_to_dict
from llm_grop.errors import BadInput
from llm_grop.evaluation import rate
from llm_grop.geometry.places import default_seats, places
from llm_grop.language.request import parse_request
from llm_grop.world.catalog import Catalog
from llm_grop.world.seat import Seat
from llm_grop.world.table import Table

CATALOG = Catalog.load(use_env=False)
PREFERENCES = ArrangeOptions(preference_pool=(
    "the dinner plate 3 cm from the diner's edge of the table",
    "the dinner fork 2 cm to the left of the dinner plate",
    "the dinner knife 2 cm to the right of the dinner plate",
))
SETTING = "a dinner plate, a dinner fork and a dinner knife"
NO_CALLS = Path(__file__).with_name("no_calls.jsonl")


def _arrange(request: str, table: Table, seed: int = 0):
    # The preferences state every relation and distance: no LLM call is made, and the
    # replay backend, given no recorded call at all, would refuse one.
    return arrange(request, llm="replay", llm_options=BackendOptions(replay_path=str(NO_CALLS)),
                   table=table, seed=seed, catalog=CATALOG, options=PREFERENCES)


@pytest.mark.parametrize(("text", "diners", "names"), [
    (f"set the table for two with {SETTING}", 2, 6),
    (f"four place settings with {SETTING}", 4, 12),
    (f"set the table for 3 people with {SETTING}", 3, 9),
    (f"set the table with {SETTING}", 1, 3),
])
def test_requests_for_several_diners(text: str, diners: int, names: int) -> None:
    req = parse_request(text, CATALOG)
    assert req.diners == diners and len(req.items) == names
    if diners > 1:
        assert [i.diner for i in req.items] == [d for d in range(diners) for _ in range(3)]
        assert req.items[3].name == "dinner plate 2"


@pytest.mark.parametrize("text", [f"set the table for 13 with {SETTING}",
                                  f"set the table for 0 with {SETTING}"])
def test_diner_counts_out_of_range(text: str) -> None:
    with pytest.raises(BadInput, match="between 1 and 12 diners"):
        parse_request(text, CATALOG)


def test_default_seats_face_the_table() -> None:
    for table, n in ((Table(1.8, 0.9), 4), (Table.circle(1.2), 5), (Table(0.6, 1.2), 2)):
        seats = default_seats(table, n)
        assert len(seats) == n
        for s, place in zip(seats, places(table.with_diners(seats), seats), strict=True):
            # The place's frame looks the way the diner faces, from their edge.
            assert place.yaw == pytest.approx(s.yaw - math.pi / 2)
            x, y = place.to_place(s.x, s.y)
            assert float(x) == pytest.approx(0.0, abs=1e-9)
            assert float(y) == pytest.approx(-place.box.depth / 2, abs=1e-3)


def test_two_diners_on_opposite_sides_get_mirror_image_settings() -> None:
    result = _arrange(f"set the table for two with {SETTING}", Table(1.8, 0.9))
    table = result.arrangement.table
    assert [s.as_list() for s in table.diners] == [[0.0, -0.45, math.pi / 2],
                                                   [0.0, 0.45, -math.pi / 2]]
    assert len(result.configurations) == 25
    for config in result.configurations:
        p = config.by_name()
        near = [p[n] for n in ("dinner plate", "dinner fork", "dinner knife")]
        far = [p[n] for n in ("dinner plate 2", "dinner fork 2", "dinner knife 2")]
        # Each setting, seen from its plate, is the other turned half round the table.
        for a, b in zip(near[1:], far[1:], strict=True):
            assert b.x - far[0].x == pytest.approx(-(a.x - near[0].x), abs=2 * GAP_TOLERANCE_M)
            assert b.y - far[0].y == pytest.approx(-(a.y - near[0].y), abs=0.05)
        assert near[1].x < near[0].x < near[2].x  # the near diner's fork on their left
        assert far[1].x > far[0].x > far[2].x     # the far diner's fork on their left too
        assert all(o.diner == 0 for o in near) and all(o.diner == 1 for o in far)
        assert all(abs(o.yaw) < 1e-9 for o in near)
        assert all(o.yaw == pytest.approx(math.pi) for o in far)
        # Each plate 3 cm from its own diner's edge.
        assert near[0].y - 0.135 + 0.45 == pytest.approx(0.03, abs=GAP_TOLERANCE_M)
        assert 0.45 - (far[0].y + 0.135) == pytest.approx(0.03, abs=GAP_TOLERANCE_M)
    for fid in result.fidelity:
        assert len(fid.gaps) == 4 and fid.max_gap_error_m <= GAP_TOLERANCE_M


def test_four_diners_at_a_round_table_are_rated_each_in_their_frame() -> None:
    result = _arrange(f"set the table for four with {SETTING}", Table.circle(1.2), seed=3)
    doc = arrangement_to_dict(result.arrangement)
    assert len(doc["table"]["diners"]) == 4
    assert sorted({o["diner"] for o in doc["objects"]}) == [0, 1, 2, 3]
    rating = rate(doc, catalog=CATALOG)
    assert len(rating.diners) == 4
    assert rating.score == min(r.score for r in rating.diners) >= 4
    # Break diner 2's setting: the table scores its lowest setting.
    for o in doc["objects"]:
        if o["name"] == "dinner fork 3":
            o["x"], o["y"] = -o["x"], -o["y"]
    broken = rate(doc, catalog=CATALOG)
    assert broken.diners[2].score < rating.diners[2].score
    assert broken.score == broken.diners[2].score
    assert "diner 2" in broken.summary


def test_too_many_diners_is_bad_input_naming_the_table_and_count() -> None:
    # Plainly too many: caught before any LLM call.
    items = parse_request(f"set the table for eight with {SETTING}", CATALOG).items
    with pytest.raises(BadInput, match=r"8 diners do not fit at the 0\.9 x 0\.6 m table"):
        seat_table(Table(), items)
    # Too many for the settings' layout: caught when the places are sampled.
    with pytest.raises(BadInput, match=r"6 diners do not fit at the 0\.9 x 0\.6 m table"):
        _arrange(f"set the table for six with {SETTING}", Table())


def test_a_seat_inside_the_table_is_bad_input() -> None:
    with pytest.raises(BadInput, match=r"diner 1's seat at \(\+0\.10, \+0\.00\) m lies inside"):
        Table(diners=(Seat(0.0, -0.3), Seat(0.1, 0.0, 0.0)))
    doc = {"request": "", "table": {"size": [0.9, 0.6], "diners": [[0, -0.3, 1.57],
                                                                   [0.2, 0.1, 0]]},
           "objects": []}
    with pytest.raises(BadInput, match="arrangement: table: diner 1's seat"):
        rate(doc, catalog=CATALOG)


def test_a_seat_facing_away_is_bad_input() -> None:
    with pytest.raises(BadInput, match="faces away"):
        places(Table(), (Seat(0.0, -0.3, -math.pi / 2),))


def test_places_do_not_overlap() -> None:
    table = Table.circle(1.2)
    seats = default_seats(table, 4)
    regions = []
    for place in places(table.with_diners(seats), seats):
        assert place.region is not None
        from shapely import affinity
        regions.append(affinity.translate(affinity.rotate(place.region, place.yaw,
                                                          origin=(0, 0), use_radians=True),
                                          *place.origin))
    for i, a in enumerate(regions):
        for b in regions[i + 1:]:
            assert a.intersection(b).area < 1e-6
    assert sum(r.area for r in regions) == pytest.approx(math.pi * 0.36, rel=0.01)
    assert np.isfinite([r.area for r in regions]).all()


def _room_with(extra: str) -> str:
    from importlib import resources
    text = resources.files("llm_grop").joinpath("data/scenes/dining_room.yaml").read_text()
    return text + extra


def test_a_scene_seats_its_diners_and_a_plain_request_serves_each() -> None:
    from llm_grop import run
    from llm_grop.files.scene_file import parse_scene, scene_to_dict
    scene = parse_scene(_room_with("diners: [[0.0, -0.3, 1.5708], [0.0, 0.3, -1.5708]]\n"),
                        "room.yaml")
    assert len(scene.target_top.diners) == 2
    assert scene_to_dict(scene)["diners"] == [[0.0, -0.3, 1.5708], [0.0, 0.3, -1.5708]]
    result = run("set the table with a dinner plate", scene=scene, seed=2, llm="replay",
                 llm_options=BackendOptions(replay_path=str(NO_CALLS)), catalog=CATALOG,
                 options=ArrangeOptions(preference_pool=(
                     "the dinner plate 2 cm from the diner's edge",)))
    assert result.success
    plates = {p.name: p for p in result.final.placements}
    assert set(plates) == {"dinner plate", "dinner plate 2"}
    assert plates["dinner plate"].y < 0 < plates["dinner plate 2"].y
    assert rate(arrangement_to_dict(result.final), catalog=CATALOG).diners


def test_a_scene_seat_inside_the_table_names_the_field() -> None:
    from llm_grop.files.scene_file import parse_scene
    with pytest.raises(BadInput, match=r"room\.yaml: diners: diner 0's seat .* lies inside"):
        parse_scene(_room_with("diners: [[0.0, 0.0, 1.5708]]\n"), "room.yaml")


def test_cli_too_many_diners_and_bad_weight_are_one_line_errors(capsys) -> None:
    from llm_grop.cli import main
    assert main(["run", f"set the table for eight with {SETTING}", "-q"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "8 diners do not fit" in err
    assert main(["run", "--task", "1", "--fidelity-weight", "-1", "-q"]) == 2


def test_bench_in_a_scene_that_seats_two_rates_each_setting(tmp_path: Path) -> None:
    import json

    from llm_grop.cli import main
    scene = tmp_path / "seated.yaml"
    scene.write_text(_room_with("diners: [[-0.45, -0.45, 1.5708], [0.45, 0.45, -1.5708]]\n"))
    prefs = tmp_path / "prefs.yaml"
    prefs.write_text("preferences:\n" + "".join(
        f"  - {s}\n" for s in PREFERENCES.preference_pool))
    out = tmp_path / "bench"
    assert main(["bench", "--tasks", "1", "--trials", "1", "--methods", "llm-grop,grop",
                 "--scene", str(scene), "--table", "1.8x0.9", "--llm", "replay",
                 "--replay", str(NO_CALLS), "--preferences", str(prefs), "--out", str(out),
                 "--no-images", "-q"]) == 0
    rows = [json.loads(line) for line in (out / "trials.jsonl").read_text().splitlines()]
    assert len(rows) == 2
    for row in rows:
        assert len(row["rating_explanation"]["diners"]) == 2
        assert row["rating"] == min(d["score"] for d in row["rating_explanation"]["diners"])
        assert len(row["final"]["table"]["diners"]) == 2


def test_one_seat_across_the_table_is_that_diner_s_setting() -> None:
    from llm_grop import run
    from llm_grop.files.scene_file import parse_scene
    scene = parse_scene(_room_with("diners: [[0.0, 0.3, -1.5708]]\n"), "room.yaml")
    result = run(f"set the table with {SETTING}", scene=scene, seed=0, llm="replay",
                 llm_options=BackendOptions(replay_path=str(NO_CALLS)), catalog=CATALOG,
                 options=PREFERENCES)
    p = {o.name: o for o in result.planned.placements}
    # The diner sits at +y facing -y: their left is +x, and the plate is near their edge.
    assert p["dinner fork"].x > p["dinner plate"].x > p["dinner knife"].x
    assert 0.3 - (p["dinner plate"].y + 0.135) == pytest.approx(0.03, abs=GAP_TOLERANCE_M)
    rating = rate(arrangement_to_dict(result.planned), catalog=CATALOG)
    assert len(rating.diners) == 1 and rating.score == rating.diners[0].score
