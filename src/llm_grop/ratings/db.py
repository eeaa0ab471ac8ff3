"""The study database: one SQLite file in WAL mode (:mod:`llm_grop.database`), its schema
kept by the migrations in ``migrations/`` beside this module."""

from __future__ import annotations

import sqlite3
from pathlib import Path

from llm_grop import database
from llm_grop.database import BUSY_TIMEOUT_MS, Migration, transaction

__all__ = ["APPLICATION_ID", "BUSY_TIMEOUT_MS", "Migration", "connect", "migrations",
           "schema_version", "transaction"]

#: ``PRAGMA application_id`` of a study database ("LGRP").
APPLICATION_ID = 0x4C475250
STUDY = database.Kind("llm_grop.ratings", APPLICATION_ID, "study database",
                      "make one with 'llm-grop ratings create'")


def migrations() -> tuple[Migration, ...]:
    """The packaged migrations, in version order."""
    return database.migrations(STUDY.package)


def schema_version() -> int:
    """The schema version this llm-grop writes."""
    return len(migrations())


def connect(path: str | Path, *, create: bool = False,
            upto: int | None = None) -> sqlite3.Connection:
    """An open connection to the study database at ``path`` (see
    :func:`llm_grop.database.connect`)."""
    return database.connect(STUDY, path, create=create, upto=upto)
