-- The report and the export read ratings by item; expired sessions are swept by time.
CREATE INDEX ratings_by_item ON ratings (item_id);
CREATE INDEX sessions_by_expiry ON sessions (expires_at);
