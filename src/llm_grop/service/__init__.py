"""``llm-grop serve``: the planning service for robot stacks and the playground page.

A FastAPI app (:mod:`.app`) answers a versioned JSON API under ``/v1/``; every request is
a job in one SQLite file (:mod:`.jobs`), run by a bounded pool of worker processes
(:mod:`.workers`) that call the public API (:mod:`llm_grop.api`) as the CLI does
(:mod:`.tasks`). Arrangements and plans are answered when their job ends; runs are
polled or followed as server-sent events.
"""
