"""Reads and sets a patient's voice setting (queries only; the router checks access and audits)."""

from __future__ import annotations

from sqlalchemy.orm import Session

from backend.voice.models import DEFAULT_ENABLED, DEFAULT_VOLUME, VoicePreference
from backend.voice.schemas import VoiceIn, VoiceOut


def _out(patient_id: int, row: VoicePreference | None) -> VoiceOut:
    if row is None:
        return VoiceOut(patient_id=patient_id, enabled=DEFAULT_ENABLED, volume=DEFAULT_VOLUME, updated_at=None)
    return VoiceOut(patient_id=patient_id, enabled=row.enabled, volume=row.volume, updated_at=row.updated_at)


def get_voice(*, db_session: Session, patient_id: int) -> VoiceOut:
    """Returns the patient's voice setting (the defaults when none is stored)."""
    return _out(patient_id, db_session.get(VoicePreference, patient_id))


def set_voice(*, db_session: Session, patient_id: int, body: VoiceIn, by_user_id: int | None) -> VoiceOut:
    """Stores the patient's voice setting; returns it."""
    row = db_session.get(VoicePreference, patient_id)
    if row is None:
        row = VoicePreference(patient_id=patient_id)
        db_session.add(row)
    row.enabled, row.volume, row.updated_by_id = body.enabled, body.volume, by_user_id
    db_session.flush()
    return _out(patient_id, row)
