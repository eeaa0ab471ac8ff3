"""The service's JSON API against a real server: answers validate against the published
schemas, and every bad input is a 4xx with the project's one-line message."""

from __future__ import annotations

import json
import re
from pathlib import Path

import httpx
import jsonschema
import pytest
import yaml

from service_support import Server, start_server, wait_done

ROOT = Path(__file__).resolve().parents[2]
SCHEMAS = ROOT / "docs" / "schema"
REQUEST = "a dinner plate, a dinner fork and a dinner knife"


def openapi_validator(name: str) -> jsonschema.Draft202012Validator:
    """A validator for the OpenAPI document's component ``name``."""
    doc = json.loads((SCHEMAS / "openapi.json").read_text(encoding="utf-8"))
    schema = {"$ref": f"#/components/schemas/{name}", "components": doc["components"]}
    return jsonschema.Draft202012Validator(schema)


def contract_validator(name: str) -> jsonschema.Draft202012Validator:
    return jsonschema.Draft202012Validator(
        json.loads((SCHEMAS / f"{name}.schema.json").read_text(encoding="utf-8")))


def test_the_published_openapi_document_is_the_servers(server: Server) -> None:
    with server.client() as c:
        served = c.get("/v1/openapi.json").json()
    published = json.loads((SCHEMAS / "openapi.json").read_text(encoding="utf-8"))
    assert served == published, "regenerate: llm-grop serve --openapi > docs/schema/openapi.json"
    assert all(p.startswith("/v1/") for p in published["paths"])


def test_an_arrangement_with_its_reading_picture_and_permalink(server: Server) -> None:
    with server.client() as c:
        r = c.post("/v1/arrangements", json={"request": REQUEST, "seed": 0})
        assert r.status_code == 200, r.text
        body = r.json()
        openapi_validator("ArrangementAnswer").validate(body)
        contract_validator("arrangement").validate(body["arrangement"])
        names = [o["name"] for o in body["arrangement"]["objects"]]
        assert names == ["dinner plate", "dinner fork", "dinner knife"]
        assert {o["source"] for o in body["reading"]["objects"]} == {"request"}
        assert body["reading"]["read_by"] == "catalog"
        picture = c.get(body["picture"])
        assert picture.status_code == 200 and picture.content[:8] == b"\x89PNG\r\n\x1a\n"
        again = c.get(body["permalink"])
        assert again.status_code == 200 and again.json() == body


def test_the_same_seed_gives_the_same_arrangement(server: Server) -> None:
    with server.client() as c:
        first, second = (c.post("/v1/arrangements", json={"request": REQUEST, "seed": 4})
                         .json() for _ in range(2))
    assert first["id"] != second["id"]
    for key in ("objects", "relations", "table"):
        assert first["arrangement"][key] == second["arrangement"][key]


def test_a_plan_a_robot_stack_executes(server: Server) -> None:
    with server.client() as c:
        r = c.post("/v1/plans", json={"task": 8, "seed": 3})
        assert r.status_code == 200, r.text
        body = r.json()
        assert c.get(body["room_picture"]).headers["content-type"] == "image/png"
    openapi_validator("PlanAnswer").validate(body)
    contract_validator("plan").validate(body["plan"])
    steps = body["plan"]["steps"]
    assert [s["action"] for s in steps[:3]] == ["navigate", "pick", "navigate"]
    assert all(0 <= s["success_p"] <= 1 and s["duration_s"] >= 0 for s in steps)
    places = [s for s in steps if s["action"] == "place"]
    assert [s["object"] for s in places] == body["plan"]["plan"]["order"]
    assert all(len(s["standing"]) == 3 and len(s["pose"]) == 3 for s in places)


def test_a_plan_carries_several_objects_per_trip(server: Server) -> None:
    # With the supplies in a kitchen next door, a trip of several objects pays.
    scene = yaml.safe_load((Path(__file__).parents[2] / "benchmarks" / "data"
                            / "kitchen_apart.yaml").read_text(encoding="utf-8"))
    with server.client() as c:
        plans = {capacity: c.post("/v1/plans", json={
            "task": 1, "seed": 3, "method": "grop", "scene": scene, "capacity": capacity})
            for capacity in (1, 3)}
        bad = c.post("/v1/plans", json={"task": 8, "capacity": 0})
    actions = {}
    for capacity, r in plans.items():
        assert r.status_code == 200, r.text
        actions[capacity] = [s["action"] for s in r.json()["plan"]["steps"] if
                             s["action"] != "navigate"]
    assert actions[1] == ["pick", "place"] * 3
    assert actions[3] == ["pick"] * 3 + ["place"] * 3
    assert bad.status_code == 422 and bad.json()["error"].startswith("capacity: ")


def test_a_run_as_a_job_with_its_events(server: Server) -> None:
    with server.client() as c:
        r = c.post("/v1/runs", json={"task": 1, "seed": 2, "method": "grop"})
        assert r.status_code == 202 and r.headers["location"] == f"/v1/runs/{r.json()['id']}"
        openapi_validator("JobAnswer").validate(r.json())
        job = wait_done(c, r.json()["id"])
        assert job["state"] == "done", job
        openapi_validator("JobAnswer").validate(job)
        contract_validator("run").validate(job["result"])
        # Every run is recorded for Rerun where the server has the [viz] extra.
        assert set(job["files"]) == {"room.png", "table.png", "table_phone.png",
                                     "episode.rrd"}
        assert c.get(job["files"]["episode.rrd"]).content[:4] == b"RRF2"
        with c.stream("GET", job["events"]) as events:
            text = "".join(events.iter_text())
    assert "event: progress" in text and "executing the plan" in text
    assert text.rstrip().endswith('data: {"state": "done", "error": null}')


BAD = [
    ("/v1/arrangements", {"request": REQUEST, "colour": "red"}, 422,
     "colour: unknown key; expected one of request, table, diners"),
    ("/v1/arrangements", {"request": REQUEST, "sead": 3}, 422,
     "sead: unknown key; did you mean 'seed'?"),
    ("/v1/arrangements", {"request": 5}, 422, "request: expected text, got 5"),
    ("/v1/arrangements", {"request": ""}, 422, "request: must not be empty, got ''"),
    ("/v1/arrangements", {"request": "a " * 300}, 422,
     "request: 600 characters; this server reads at most 500"),
    ("/v1/arrangements", {"request": "a " * 1001}, 422, "request: must be at most 2000 characters"),
    ("/v1/arrangements", {"request": REQUEST, "seed": -1}, 422, "seed: must be at least 0, got -1"),
    ("/v1/arrangements", {"request": REQUEST, "revisions": 11}, 422,
     "revisions: must be at most 10, got 11"),
    ("/v1/arrangements", {"request": REQUEST, "llm": "/etc/passwd"}, 422,
     "llm: '/etc/passwd' looks like a file path"),
    ("/v1/arrangements", {"request": REQUEST, "llm": "openai"}, 422,
     "llm: this server offers no backend 'openai'; choose 'replay'"),
    ("/v1/arrangements", {"request": REQUEST, "table": {"size": [12, 0.6]}}, 422,
     "table.size[0]: must be at most 10, got 12"),
    ("/v1/plans", {"task": 8, "scene": "/tmp/room.yaml"}, 422,
     "scene: expected an object, got '/tmp/room.yaml'"),
    ("/v1/plans", {"task": 8, "catalog": "../catalog.yaml"}, 422,
     "catalog: unknown key; expected one of request, task, arrangement"),
    ("/v1/plans", {"task": 8, "method": "nope"}, 422, "method: unknown method 'nope'"),
    ("/v1/plans", {"task": 8, "method": "../x"}, 422, "looks like a file path"),
    ("/v1/plans", {}, 422, "request: give one of request, task or arrangement"),
    ("/v1/plans", {"task": 8, "scene": {"room": {"width": 5}}}, 422, "scene: "),
    ("/v1/plans", {"request": "twelve water cups, twelve wine glasses and six napkins",
                   "method": "grop"}, 409,
     "the supply tables hold 26 of the 30 objects: 'napkin 3', 'napkin 4', 'napkin 5', "
     "'napkin 6' do not fit"),
    ("/v1/plans", {"task": 8, "scene": {"room": {"width": 5, "depth": 5}, "target": "t",
                                        "tables": [{"name": "t", "center": [1, 1],
                                                    "size": [0.5, 0.5]}] * 101}}, 422,
     "scene.tables: 101 entries; this server takes at most 100"),
    ("/v1/runs", {"task": 8, "simulator": "bullet"}, 422, "simulator: unknown simulator"),
    ("/v1/runs", {"task": 8, "simulator": "mujoco", "sim_options": {"video_path": "/tmp/x"}},
     422,
     "sim_options.video_path: names a file on the server"),
    ("/v1/runs", {"task": 8, "sim_options": {"timestep": 0.1}}, 422,
     "sim_options.timestep: simulator 'kinematic2d' has no option 'timestep'"),
    ("/v1/runs", {"task": 8, "simulator": "mujoco", "sim_options": {"timestep_s": "fast"}},
     422, "sim_options.timestep_s: "),
    ("/v1/plans", {"task": 8, "method": "tpra", "method_options": {"draw_box": "room"}}, 422,
     "method_options.draw_box: expected one of 'authors' or 'place'"),
    ("/v1/plans", {"task": 8, "method_options": {"draw_box": "place"}}, 422,
     "method 'llm-grop' has no option 'draw_box'"),
    ("/v1/plans", {"task": 8, "method_options": {"k": {"deep": 1}}}, 422, "method_options.k"),
    ("/v1/arrangements", {"request": REQUEST, "preferences": ["the mug near the plate"]}, 422,
     "preferences: 'the mug near the plate': cannot read it as a relation"),
]


@pytest.mark.parametrize(("path", "body", "status", "words"), BAD,
                         ids=[f"{p}-{i}" for i, (p, *_rest) in enumerate(BAD)])
def test_bad_input_is_a_4xx_with_one_line(server: Server, path: str, body: dict,
                                          status: int, words: str) -> None:
    with server.client() as c:
        r = c.post(path, json=body)
    assert r.status_code == status, r.text
    answer = r.json()
    openapi_validator("ErrorAnswer").validate(answer)
    assert words in answer["error"] and "\n" not in answer["error"]
    assert "Traceback" not in r.text


def test_malformed_json_and_unknown_paths(server: Server) -> None:
    with server.client() as c:
        r = c.post("/v1/arrangements", content=b"{not json", headers={
            "content-type": "application/json"})
        assert r.status_code == 422 and r.json()["code"] == "bad_json"
        r = c.get("/v1/runs/nope")
        assert r.status_code == 404 and r.json() == {
            "error": "no run job 'nope' on this server", "code": "not_found"}
        assert c.get("/v1/files/nope/table.png").status_code == 404


def test_oversized_bodies_get_413_declared_or_chunked(server: Server) -> None:
    big = b'{"request": "' + b"a" * (300 * 1024) + b'"}'
    with server.client() as c:
        r = c.post("/v1/arrangements", content=big,
                   headers={"content-type": "application/json"})
        assert r.status_code == 413 and "larger than" in r.json()["error"]

        def chunks():
            for k in range(0, len(big), 4096):
                yield big[k:k + 4096]

        r = c.post("/v1/arrangements", content=chunks(),
                   headers={"content-type": "application/json"})
        assert r.status_code == 413


def test_one_client_may_not_queue_without_bound(tmp_path: Path) -> None:
    from service_support import start_server

    s = start_server(tmp_path / "jobs.sqlite", "--workers", "1", "--queue", "3")
    try:
        with s.client() as c:
            codes = [c.post("/v1/runs", json={"task": 8, "seed": k}) for k in range(8)]
    finally:
        s.stop()
    refused = [r for r in codes if r.status_code == 429]
    assert refused and all(r.headers["retry-after"].isdigit() for r in refused)
    assert all(r.status_code in (202, 429) for r in codes)


def test_a_token_is_needed_and_checked(tmp_path: Path) -> None:
    from service_support import start_server

    token = "t/+=" * 6  # characters a cookie must quote
    s = start_server(tmp_path / "jobs.sqlite", token=token)
    try:
        assert httpx.get(f"{s.url}/v1/info").status_code == 401
        wrong = httpx.get(f"{s.url}/v1/info", headers={"Authorization": "Bearer " + "x" * 24})
        assert wrong.status_code == 401 and wrong.json()["code"] == "unauthorized"
        with s.client() as c:
            assert c.get("/v1/info").status_code == 200
        # A browser opens /?token=... once; the cookie then opens the pages, not the API.
        with httpx.Client(base_url=s.url) as browser:
            login = browser.get("/", params={"token": token})
            assert login.status_code == 303 and "HttpOnly" in login.headers["set-cookie"]
            assert browser.get("/").status_code == 200
            assert browser.post("/v1/arrangements", json={"request": REQUEST}
                                ).status_code == 401
    finally:
        s.stop()


def test_a_failing_llm_is_the_servers_fault_and_names_nothing_of_it(server: Server) -> None:
    with server.client() as c:
        r = c.post("/v1/arrangements", json={"request": "a dinner plate and a flying saucer"})
    assert r.status_code == 503, r.text
    assert r.json() == {"error": "llm: the server's LLM backend could not answer this "
                                 "request; its log says why", "code": "llm_unavailable"}
    assert "jsonl" not in r.text  # the server's replay file stays on the server


def test_only_json_and_only_this_machines_names(server: Server) -> None:
    with server.client() as c:
        r = c.post("/v1/arrangements", content=json.dumps({"request": REQUEST}),
                   headers={"content-type": "text/plain"})
        assert r.status_code == 415 and r.json()["code"] == "not_json"
        r = c.get("/v1/info", headers={"host": "evil.example:8000"})
        assert r.status_code == 400 and "answers only to 127.0.0.1" in r.json()["error"]
        assert c.get("/v1/info", headers={"host": "localhost"}).status_code == 200


def test_a_form_from_another_site_is_refused(server: Server) -> None:
    form = {"request": REQUEST, "action": "arrange"}
    with server.client() as c:
        for origin in ("http://evil.example", "null", None):
            headers = {"origin": origin} if origin else {}
            r = c.post("/play", data=form, headers=headers)
            assert r.status_code == 403 and "another site" in r.text
        r = c.post("/play", data=form, headers={"origin": server.url})
        assert r.status_code == 303 and r.headers["location"].startswith("/a/")


def test_a_video_is_served_in_ranges(server: Server) -> None:
    with server.client() as c:
        job = c.post("/v1/arrangements", json={"request": REQUEST}).json()
        whole = c.get(job["picture"]).content
        part = c.get(job["picture"], headers={"range": "bytes=10-19"})
        assert part.status_code == 206 and part.content == whole[10:20]
        assert part.headers["content-range"] == f"bytes 10-19/{len(whole)}"
        assert c.get(job["picture"], headers={"range": "bytes=-5"}).content == whole[-5:]
        bad = c.get(job["picture"], headers={"range": f"bytes={len(whole)}-"})
        assert bad.status_code == 416 and bad.json()["code"] == "bad_range"


def test_info_gives_counts_and_bytes_as_whole_numbers(server: Server) -> None:
    with server.client() as c:
        limits = c.get("/v1/info").json()["limits"]
    for name in ("body_bytes", "body_depth", "request_chars", "objects", "queue",
                 "jobs_per_client"):
        assert isinstance(limits[name], int), (name, limits[name])
    assert '"body_bytes": 262144,' in json.dumps(limits) + ","


def test_the_playground_serves_its_icon(server: Server) -> None:
    with server.client(follow_redirects=True) as c:
        icon = c.get("/favicon.ico")
        page = c.get("/")
    assert icon.status_code == 200 and icon.headers["content-type"].startswith("image/svg")
    assert 'rel="icon" href="/static/favicon.svg"' in page.text


@pytest.mark.parametrize(("diners", "caption"), [
    (1, "(the diner sits at the bottom)"),
    (2, "(2 diners, each drawn at their seat and labelled)")])
def test_the_playgrounds_caption_says_where_the_diners_sit(server: Server, diners: int,
                                                           caption: str) -> None:
    with server.client() as c:
        r = c.post("/v1/arrangements", json={"request": "a dinner plate", "diners": diners})
        assert r.status_code == 200, r.text
        job_id = r.json()["permalink"].rstrip("/").rsplit("/", 1)[-1]
        page = c.get(f"/a/{job_id}")
    assert page.status_code == 200 and caption in page.text


def test_a_plan_seats_the_diners_it_is_given(server: Server) -> None:
    with server.client() as c:
        r = c.post("/v1/plans", json={"task": 1, "seed": 2, "method": "grop", "diners": 3,
                                      "table": {"size": [1.8, 0.9]}})
        assert r.status_code == 200, r.text
        plan = r.json()["plan"]
    places = [s["object"] for s in plan["steps"] if s["action"] == "place"]
    assert len(places) == 9 and "dinner plate 3" in places  # task 1's three, thrice


@pytest.mark.parametrize("guess", ["on", "off"])
def test_the_playground_offers_guess_as_its_own_control(server: Server, guess: str) -> None:
    form = {"request": "a dinner plate", "action": "arrange", "guess": guess}
    with server.client(follow_redirects=True) as c:
        page = c.post("/play", data=form, headers={"origin": server.url})
    assert page.status_code == 200, page.text
    chosen = re.search(r'<select name="guess">.*?</select>', page.text, flags=re.S)
    assert chosen and f'<option value="{guess}" selected>' in chosen[0]


def test_the_playground_words_warnings_with_its_own_controls() -> None:
    from llm_grop.settings import words

    warning = ("the embedded LLM chose what the request does not say: 2 bread; "
               "guess=False refuses this")
    assert words(warning, "web").endswith(
        '2 bread; the "refuse the request" choice for the objects a request leaves out '
        "refuses this")
    assert words("m=0 is too few", "web") == '"m": 0 is too few'


def test_serve_offers_what_llm_auto_finds_at_start(tmp_path: Path, chat_server,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    port = chat_server.url.split(":")[2].split("/")[0]
    monkeypatch.setenv("LLM_GROP_PROBE_PORTS", port)
    s = start_server(tmp_path / "jobs.sqlite", "--llm", "auto")
    try:
        with s.client() as c:
            assert c.get("/v1/info").json()["backends"] == ["replay", "openai"]
    finally:
        s.stop()
    log = (tmp_path / "jobs.sqlite.log").read_text()
    assert f"--llm auto: using openai local-model: a server answered on 127.0.0.1:{port}" \
        in log


def test_preferences_learned_from_example_settings(server: Server) -> None:
    """``POST /v1/preferences`` learns as ``llm-grop learn`` does, from the settings in the
    body."""
    from learning_support import LEFT_HANDED, arranged

    examples = [arranged(LEFT_HANDED, seed) for seed in (1, 2)]
    with server.client() as c:
        answer = c.post("/v1/preferences", json={"examples": examples})
    assert answer.status_code == 200, answer.text
    data = answer.json()
    sentences = [p["sentence"] for p in data["preferences"]]
    assert any(s.startswith("the dinner fork ") and s.endswith(" to the right of the dinner "
                                                               "plate") for s in sentences)
    assert all(p["examples"] == ["example 1", "example 2"] for p in data["preferences"])
    assert data["file"].startswith("# Preferences learned") and data["not_learned"] == []


def test_arrangements_and_plans_take_example_settings(server: Server) -> None:
    """A body's ``examples`` apply as ``--examples`` does: the left-handed fork goes right
    of the plate, with source ``learned`` and the settings it was read off."""
    from learning_support import LEFT_HANDED, arranged

    examples = [arranged(LEFT_HANDED, seed) for seed in (1, 2)]
    with server.client() as c:
        arranged_answer = c.post("/v1/arrangements", json={"request": REQUEST, "seed": 0,
                                                           "examples": examples})
        planned = c.post("/v1/plans", json={"task": 1, "seed": 0, "examples": examples})
        bad = c.post("/v1/arrangements", json={"request": REQUEST, "examples": [{}]})
    for answer, doc in ((arranged_answer, "arrangement"), (planned, "plan")):
        assert answer.status_code == 200, answer.text
        relations = answer.json()["reading"]["relations"]
        (fork,) = [r for r in relations if r["subject"] == "dinner fork"]
        assert (fork["relation"], fork["reference"], fork["source"], fork["examples"]) == (
            "to the right of", "dinner plate", "learned", ["example 1", "example 2"]), doc
    assert bad.status_code == 422 and bad.json()["error"].startswith("example 1: ")


def test_preferences_generalised_by_the_servers_llm_as_a_job(tmp_path: Path,
                                                               chat_server) -> None:
    """With ``generalise``, the server's LLM gives rules for the objects the examples do
    not show (a real local server answering as a model would), as ``llm-grop learn``."""
    from learning_support import LEFT_HANDED, arranged

    chat_server.reply = lambda body: "Place the water cup above and to the left of the " \
                                     "dinner plate."
    examples = [arranged(LEFT_HANDED, seed) for seed in (1, 2)]
    s = start_server(tmp_path / "jobs.sqlite", "--llm", "openai", "--base-url",
                     chat_server.url, "--model", "qwen2.5:7b")
    try:
        with s.client() as c:
            answer = c.post("/v1/preferences", json={"examples": examples, "seed": 3,
                                                     "generalise": True, "llm": "openai"})
            assert answer.status_code == 200, answer.text
            data = answer.json()
            again = c.get(data["permalink"])
            exact = c.post("/v1/preferences", json={"examples": examples}).json()
            bad = c.post("/v1/preferences", json={"examples": examples, "generalise": True,
                                                  "llm": "embedded"})
    finally:
        s.stop()
    openapi_validator("PreferencesAnswer").validate(data)
    (rule,) = [p for p in data["preferences"] if p["examples"] == ["a rule by qwen2.5:7b"]]
    assert rule["sentence"].startswith("the water cup ") and rule["sentence"].endswith(
        " cm above and to the left of the dinner plate")
    assert data["permalink"] == f"/v1/preferences/{data['id']}" and again.json() == data
    assert [p for p in data["preferences"] if p != rule] == exact["preferences"]
    assert exact["id"] is None and len(chat_server.requests) == 1
    assert bad.status_code == 422 and bad.json()["error"].startswith("llm: ")


@pytest.mark.parametrize(("body", "needle"), [
    ({"examples": []}, "examples: must not be empty"),
    ({"examples": [{}]}, "example 1: "),
    ({"examples": [{"objects": []}], "sead": 1}, "sead: unknown key"),
])
def test_bad_examples_are_one_line(server: Server, body: dict, needle: str) -> None:
    with server.client() as c:
        answer = c.post("/v1/preferences", json=body)
    assert answer.status_code in (400, 422), answer.text
    assert needle in answer.json()["error"]
