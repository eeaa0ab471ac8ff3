-- A study: the pictures of one bench's trials, the raters invited to rate them, each
-- rater's own order, their sessions and their ratings.
CREATE TABLE study (
    id INTEGER PRIMARY KEY,
    name TEXT NOT NULL,
    source TEXT NOT NULL,          -- the bench directory it was made from
    seed INTEGER NOT NULL,         -- seeds each rater's order (stage ratings.order)
    created_at TEXT NOT NULL       -- ISO 8601, UTC
);

CREATE TABLE items (
    id TEXT PRIMARY KEY,           -- random and opaque: nothing in it hints at the method
    study_id INTEGER NOT NULL REFERENCES study(id),
    position INTEGER NOT NULL,     -- the bench's (task, trial, method) order
    task INTEGER NOT NULL,
    trial INTEGER NOT NULL,
    seed INTEGER NOT NULL,
    method TEXT NOT NULL,
    objects TEXT NOT NULL,         -- JSON list of the requested objects
    automatic_rating INTEGER,      -- the automatic rater's 1-5 score
    execution_time_s REAL,         -- simulated seconds; NULL without a plan
    success INTEGER NOT NULL,
    picture BLOB NOT NULL,         -- PNG, with no metadata
    picture_source TEXT NOT NULL,  -- the picture's path in the bench directory
    UNIQUE (study_id, position)
);

CREATE TABLE raters (
    id INTEGER PRIMARY KEY,
    study_id INTEGER NOT NULL REFERENCES study(id),
    code TEXT NOT NULL UNIQUE,     -- the invite code, normalised
    label TEXT NOT NULL,           -- "r1", "r2", ...: how exports and reports name them
    created_at TEXT NOT NULL
);

CREATE TABLE rater_items (
    rater_id INTEGER NOT NULL REFERENCES raters(id),
    position INTEGER NOT NULL,     -- this rater's randomised order
    item_id TEXT NOT NULL REFERENCES items(id),
    PRIMARY KEY (rater_id, position),
    UNIQUE (rater_id, item_id)
);

CREATE TABLE sessions (
    token_hash TEXT PRIMARY KEY,   -- SHA-256 of the cookie's token; the token is not kept
    rater_id INTEGER NOT NULL REFERENCES raters(id),
    csrf TEXT NOT NULL,
    expires_at REAL NOT NULL       -- Unix seconds
);

CREATE TABLE ratings (
    rater_id INTEGER NOT NULL REFERENCES raters(id),
    item_id TEXT NOT NULL REFERENCES items(id),
    rating INTEGER NOT NULL CHECK (rating BETWEEN 1 AND 5),
    rated_at TEXT NOT NULL,
    PRIMARY KEY (rater_id, item_id)
);
