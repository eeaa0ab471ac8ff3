-- Jobs of a fourth kind: learning preferences from example settings with the LLM's step
-- (POST /v1/preferences with "generalise"). SQLite cannot change a CHECK constraint in
-- place, so the three tables are rebuilt: the children are copied before their parent
-- is dropped (with foreign keys on, dropping a parent first would cascade its rows
-- away), and renaming the new parent rewrites the children's references to it.
CREATE TABLE jobs_new (
    id TEXT PRIMARY KEY,
    kind TEXT NOT NULL CHECK (kind IN ('arrange', 'plan', 'run', 'learn')),
    body TEXT NOT NULL,
    client TEXT NOT NULL,
    priority INTEGER NOT NULL,
    state TEXT NOT NULL CHECK (state IN ('queued', 'running', 'done', 'failed', 'cancelled')),
    attempts INTEGER NOT NULL DEFAULT 0,
    claim TEXT,
    worker INTEGER,
    cancel INTEGER NOT NULL DEFAULT 0,
    created REAL NOT NULL,
    started REAL,
    finished REAL,
    status INTEGER,
    error TEXT,
    result TEXT
);
INSERT INTO jobs_new SELECT id, kind, body, client, priority, state, attempts, claim,
    worker, cancel, created, started, finished, status, error, result FROM jobs;
CREATE TABLE files_new (
    job TEXT NOT NULL REFERENCES jobs_new (id) ON DELETE CASCADE,
    name TEXT NOT NULL,
    media_type TEXT NOT NULL,
    data BLOB NOT NULL,
    PRIMARY KEY (job, name)
);
INSERT INTO files_new SELECT job, name, media_type, data FROM files;
CREATE TABLE events_new (
    job TEXT NOT NULL REFERENCES jobs_new (id) ON DELETE CASCADE,
    seq INTEGER NOT NULL,
    at REAL NOT NULL,
    message TEXT NOT NULL,
    PRIMARY KEY (job, seq)
);
INSERT INTO events_new SELECT job, seq, at, message FROM events;
DROP TABLE events;
DROP TABLE files;
DROP TABLE jobs;
ALTER TABLE jobs_new RENAME TO jobs;
ALTER TABLE files_new RENAME TO files;
ALTER TABLE events_new RENAME TO events;
CREATE INDEX jobs_queue ON jobs (state, priority);
CREATE INDEX jobs_client ON jobs (client, state);
