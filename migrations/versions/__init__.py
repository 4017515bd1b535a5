"""Alembic revision files (date + slug)."""
