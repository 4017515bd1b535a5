"""Revoking an API token or a device, or deactivating a patient, sends the end of access (ACCESS_ENDED) that ends
exactly the event streams opened with that credential (tests/frontend/test_stream_ends_with_revocation.py checks
the stream itself ends within 2 s on a real server)."""

from __future__ import annotations

import asyncio
from typing import Any

from backend.devices.service import revoke
from backend.events.hub import ACCESS_ENDED, Hub, pending
from backend.users.service import create_api_token, revoke_api_token, update_user


def _pending_ends(db_session) -> list[Any]:
    return [ev for ev in pending(db_session) if ev.kind == ACCESS_ENDED]


def _ended(streams: dict[str, Any], events: list[Any]) -> set[str]:
    """Returns the names of the streams (name -> subscribe kwargs) that the events end."""

    async def run():
        hub = Hub()
        subs = {name: hub.subscribe(frozenset({1}), **kw) for name, kw in streams.items()}
        for ev in events:
            hub.deliver(ev)
        await asyncio.sleep(0)
        return {name for name, sub in subs.items() if sub.queue.qsize()}

    return asyncio.run(run())


def test_revoking_a_token_ends_the_streams_of_it_and_of_tokens_made_with_it(db_session, make_user):
    user = make_user("patient")
    parent, _ = create_api_token(db_session=db_session, user=user, name="a", scopes=["read"], days=1)
    child, _ = create_api_token(db_session=db_session, user=user, name="b", scopes=["read"], days=1, parent=parent)
    other, _ = create_api_token(db_session=db_session, user=user, name="c", scopes=["read"], days=1)
    revoke_api_token(db_session=db_session, user=user, token_id=parent.id)
    streams = {name: {"user_id": user.id, "token_id": t.id} for name, t in (("a", parent), ("b", child), ("c", other))}
    assert _ended(streams, _pending_ends(db_session)) == {"a", "b"}


def test_revoking_a_device_ends_its_streams_only(db_session, make_user, device_headers):
    patient = make_user("patient")
    device, _ = device_headers(patient)
    other, _ = device_headers(patient)
    revoke(db_session=db_session, device=device)
    streams = {"revoked": {"user_id": patient.id, "device_id": device.id},
               "other": {"user_id": patient.id, "device_id": other.id}}  # fmt: skip
    ends = _pending_ends(db_session)
    assert _ended(streams, ends) == {"revoked"}


def test_deactivating_a_patient_ends_the_streams_of_their_devices(db_session, make_user, device_headers):
    patient = make_user("patient")
    device, _ = device_headers(patient)
    update_user(db_session=db_session, user=patient, is_active=False)
    assert _ended({"device": {"user_id": patient.id, "device_id": device.id}}, _pending_ends(db_session)) == {"device"}
