"""Schemathesis fuzzing of the whole API from its OpenAPI schema: no request may cause a 5xx, and every answer
agrees with the document (status codes, content types, bodies and headers as documented; invalid input refused).

Every operation gets a few deterministic examples (positive and negative generation), each sent as an admin and
as a therapist with one assigned patient; a few hundred requests in all. Runs inside the test transaction.
"""

from __future__ import annotations

from typing import Any

import schemathesis
from hypothesis import HealthCheck, given, settings
from schemathesis import GenerationMode
from schemathesis.checks import not_a_server_error
from schemathesis.core.result import Ok
from schemathesis.specs.openapi.checks import (
    content_type_conformance,
    negative_data_rejection,
    response_headers_conformance,
    response_schema_conformance,
    status_code_conformance,
)

EXAMPLES_PER_OPERATION = 3
CHECKS = [
    not_a_server_error,
    status_code_conformance,
    content_type_conformance,
    response_schema_conformance,
    response_headers_conformance,
    negative_data_rejection,
]


def _fuzz(operation, mode, callers: list[dict[str, Any]], failures: list[str], sent: list[int]) -> None:
    """Sends EXAMPLES_PER_OPERATION generated cases of one operation as every caller; records answers that fail a
    check."""

    @given(case=operation.as_strategy(generation_mode=mode))
    @settings(
        max_examples=EXAMPLES_PER_OPERATION,
        derandomize=True,
        deadline=None,
        database=None,
        suppress_health_check=list(HealthCheck),
    )
    def run(case) -> None:
        for headers in callers:
            response = case.call(headers=headers)
            sent.append(response.status_code)
            try:
                case.validate_response(response, checks=CHECKS)
            except BaseException as exc:  # noqa: BLE001 - a FailureGroup; collect every failing operation
                failures.append(f"{operation.method.upper()} {operation.path}: {exc}"[:500])
                return

    run()


def test_api_answers_as_documented(app, make_user, make_patient_with_therapist, auth_headers, exercise):
    _, therapist = make_patient_with_therapist()
    callers = [auth_headers(make_user("admin")), auth_headers(therapist)]
    schema = schemathesis.openapi.from_asgi("/openapi.json", app)
    operations = []
    for result in schema.get_all_operations():
        assert isinstance(result, Ok), result  # every operation of the app's schema loads
        operations.append(result.ok())
    assert len(operations) >= 20
    failures: list[str] = []
    sent: list[int] = []
    for operation in operations:
        for mode in (GenerationMode.POSITIVE, GenerationMode.NEGATIVE):
            _fuzz(operation, mode, callers, failures, sent)
    assert not failures, "\n".join(failures)
    assert len(sent) >= 100, len(sent)
    assert any(200 <= code < 300 for code in sent), "no request succeeded: the fuzzer only tested error paths"
