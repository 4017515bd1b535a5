"""Migration advicelang_0016: suggestion.params. A rule's advice stored before it is upgraded (given params) only when
the text its rule, numbers, session and day write in one of the languages is exactly its stored text; a therapist's,
an edited or an unrecognised text keeps its text and no params. Downgrade drops the column, every text kept."""

from __future__ import annotations

import datetime as dt
import uuid

import sqlalchemy as sa

from backend.i18n import translator
from backend.migrate import downgrade, upgrade
from backend.suggestions.rules import AdviceParams, advice_text

BEFORE = "records_0015_removed_at"
WRITTEN = dt.datetime(2026, 11, 24, 9, 0, tzinfo=dt.UTC)  # a Tuesday
STARTED = dt.datetime(2026, 11, 23, 18, 0, tzinfo=dt.UTC)  # the Monday before
USER = sa.table("user", *(sa.column(c) for c in ("id", "email", "full_name", "role", "is_active", "created_at")))
EXERCISE = sa.table("exercise", *(sa.column(c) for c in ("id", "slug", "name", "instructions", "plane", "pose",
                                                          "normal_range_min_deg", "normal_range_max_deg",
                                                          "created_at")),
                    sa.column("defining_angles", sa.JSON))  # fmt: skip
SESSION = sa.table("exercise_session", sa.column("id"), sa.column("client_session_id", sa.Uuid),
                   *(sa.column(c) for c in ("patient_id", "exercise_id", "started_at", "duration_s", "n_frames",
                                            "file_size", "content_hash", "processing_version", "status",
                                            "created_at")),
                   sa.column("processing_params", sa.JSON))  # fmt: skip
SUGGESTION = sa.table("suggestion", *(sa.column(c) for c in ("id", "patient_id", "session_id", "source", "rule",
                                                              "metric", "comparison", "threshold", "value", "text",
                                                              "status", "created_at")))  # fmt: skip

# texts as the rules wrote them before this migration (copied from what that code wrote, not from today's code)
FEWER_EN = ("On Monday you did 6 of the 10 mini squats in your plan. Next time, try to do all 10. Rest for a moment "
            "between them if you need to.")  # fmt: skip
PAIN_DE = ("Am Montag haben Sie nach der Übung „Kleine Kniebeuge“ Schmerzen von 8 von 10 angegeben. Machen Sie die "
           "Übung sanft und nur so weit, wie es angenehm ist. Hören Sie auf, wenn die Schmerzen stärker werden, und "
           "sagen Sie Ihrem Therapeuten, wie es Ihnen geht.")  # fmt: skip
RISING_EN = (
    "In the last week you said more pain after your exercises than before: about 5 of 10, while it was "
    "about 2.5 of 10 in the weeks before. Do your exercises gently, and tell your therapist how you feel."
)


def _stored(when: dt.datetime, dialect: str) -> dt.datetime:
    return when.replace(tzinfo=None) if dialect == "sqlite" else when


def test_old_advice_is_upgraded_only_when_recognised_for_certain(fresh_engine):
    dialect = fresh_engine.dialect.name
    with fresh_engine.begin() as conn:
        upgrade(conn, BEFORE)
        conn.execute(sa.insert(USER).values(id=1, email="p@x.org", full_name="P", role="patient", is_active=True,
                                            created_at=_stored(STARTED, dialect)))  # fmt: skip
        conn.execute(sa.insert(EXERCISE).values(id=1, slug="squat", name="Mini squat", instructions="",
                                                plane="sagittal", pose="standing", normal_range_min_deg=0,
                                                normal_range_max_deg=120,
                                                defining_angles=["knee_flexion_left"],
                                                created_at=_stored(STARTED, dialect)))  # fmt: skip
        conn.execute(sa.insert(SESSION).values(id=1, client_session_id=uuid.uuid4(), patient_id=1, exercise_id=1,
                                               started_at=_stored(STARTED, dialect), duration_s=1.0, n_frames=30,
                                               file_size=1, content_hash="0" * 64, processing_version="",
                                               status="processed", created_at=_stored(STARTED, dialect),
                                               processing_params={}))  # fmt: skip
        rows = {
            1: ("system", "fewer_reps", "repetitions", "<", 10.0, 6.0, FEWER_EN),
            2: ("system", "pain_high", "pain_nrs", ">", 5.0, 8.0, PAIN_DE),
            3: ("system", "pain_rising", "pain_nrs_median_7d", ">=", 4.5, 5.0, RISING_EN),
            4: ("system", "fewer_reps", "repetitions", "<", 10.0, 6.0, FEWER_EN.replace("Monday", "Sunday")),
            5: ("system", "fewer_reps", "repetitions", "<", 10.0, 7.0, FEWER_EN),  # numbers and text disagree
            6: ("therapist", "therapist", "", "", None, None, "Slower, please."),
            7: ("system", "a_rule_since_removed", "x", "<", 1.0, 0.0, "Old words."),
        }
        for sid, (source, rule, metric, comparison, threshold, value, text) in rows.items():
            conn.execute(sa.insert(SUGGESTION).values(id=sid, patient_id=1, session_id=1, source=source, rule=rule,
                                                      metric=metric, comparison=comparison, threshold=threshold,
                                                      value=value, text=text, status="approved",
                                                      created_at=_stored(WRITTEN, dialect)))  # fmt: skip
        upgrade(conn, "head")
    with fresh_engine.connect() as conn:
        got = {i: (text, params) for i, text, params in
               conn.execute(sa.text("SELECT id, text, params FROM suggestion ORDER BY id")).all()}  # fmt: skip
    params = {i: AdviceParams.model_validate_json(p) if isinstance(p, str) else
              None if p is None else AdviceParams.model_validate(p) for i, (_, p) in got.items()}  # fmt: skip
    assert {i for i, p in params.items() if p is not None} == {1, 2, 3}, got
    assert all(got[i][0] == rows[i][6] for i in rows), "every text is kept"
    first, second, third = params[1], params[2], params[3]
    assert first is not None and second is not None and third is not None
    assert first.session_on == STARTED.date() and first.written_on == WRITTEN.date()
    assert (first.repetitions, first.goal, first.exercise) == (6.0, 10, "squat")
    assert advice_text("pain_high", "pain_nrs", second, translator("en")).startswith(
        "On Monday you said your pain was 8 of 10 after your mini squats."
    )
    assert "etwa 5 von 10" in advice_text("pain_rising", "pain_nrs_median_7d", third, translator("de"))
    with fresh_engine.begin() as conn:
        downgrade(conn, BEFORE)
    with fresh_engine.connect() as conn:
        assert "params" not in {c["name"] for c in sa.inspect(conn).get_columns("suggestion")}
        texts = dict(conn.execute(sa.text("SELECT id, text FROM suggestion")).all())
    assert texts == {i: r[6] for i, r in rows.items()}
