"""The real coaching server for the agent's upload tests: its fixtures, shared by every test here."""

from tests.kinect_agent._backend import (  # noqa: F401  (fixtures)
    app,
    auth_headers,
    db_connection,
    db_session,
    engine,
    live_server,
    make_patient_with_therapist,
    make_user,
    pairing_code,
    settings,
    test_database_url,
)
