"""Alembic migrations of the coaching server database."""
