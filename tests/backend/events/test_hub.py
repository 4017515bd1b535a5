"""Events go out once, only for committed changes: in-process on SQLite, through LISTEN/NOTIFY on PostgreSQL."""

from __future__ import annotations

import asyncio
import os

import pytest
from sqlalchemy import create_engine, text
from sqlalchemy.orm import Session

from backend.events.hub import ACCESS_ENDED, HUB, Event, Hub, publish
from backend.events.listener import Listener, conninfo

PG_URL = os.environ.get("COACH_TEST_DATABASE_URL", "")


def test_event_json_round_trips_and_refuses_other_text():
    ev = Event("session.stored", 7, {"session_id": 3})
    assert Event.from_json(ev.to_json()) == ev
    for bad in ('{"kind": "hacked", "patient_id": 1}', '{"kind": "plan.changed", "patient_id": "1"}', "[1]"):
        with pytest.raises(ValueError, match="not an event"):
            Event.from_json(bad)


def test_hub_gives_each_subscriber_only_the_patients_it_may_see():
    async def run():
        hub = Hub()
        mine, everyone = hub.subscribe(frozenset({1})), hub.subscribe(None)
        assert hub.deliver(Event("plan.changed", 2)) == 1
        assert hub.deliver(Event("plan.changed", 1)) == 2
        await asyncio.sleep(0)
        got_mine = [mine.queue.get_nowait().patient_id for _ in range(mine.queue.qsize())]
        got_all = [everyone.queue.get_nowait().patient_id for _ in range(everyone.queue.qsize())]
        hub.unsubscribe(mine)
        assert hub.count() == 1
        return got_mine, got_all

    assert asyncio.run(run()) == ([1], [2, 1])


def test_the_end_of_a_login_reaches_only_its_own_streams():
    async def run():
        hub = Hub()
        login_7 = hub.subscribe(None, user_id=3, login_id=7)
        login_8 = hub.subscribe(None, user_id=3, login_id=8)  # the same user in another browser
        other = hub.subscribe(None, user_id=4, login_id=9)
        one = hub.deliver(Event(ACCESS_ENDED, 0, {"login_session_id": 7}))  # a logout
        every = hub.deliver(Event(ACCESS_ENDED, 0, {"user_id": 3}))  # a new password, a deactivation
        assert hub.deliver(Event("plan.changed", 1)) == 3  # the end of a login is no filter of data events
        await asyncio.sleep(0)
        return one, every, login_7.queue.qsize(), login_8.queue.qsize(), other.queue.qsize()

    assert asyncio.run(run()) == (1, 2, 3, 2, 1)
    ev = Event(ACCESS_ENDED, 0, {"user_id": 3})
    assert Event.from_json(ev.to_json()) == ev  # it travels between processes like any other event


def _received(sub, timeout: float = 5.0) -> list[Event]:
    async def drain():
        out: list[Event] = []
        try:
            while True:
                out.append(await asyncio.wait_for(sub.queue.get(), timeout=timeout if not out else 0.3))
        except TimeoutError:
            return out

    return asyncio.get_event_loop().run_until_complete(drain())


@pytest.fixture
def loop():
    loop = asyncio.new_event_loop()
    asyncio.set_event_loop(loop)
    yield loop
    loop.close()
    asyncio.set_event_loop(None)


def _subscribe(loop, patients):
    async def make():
        return HUB.subscribe(patients)

    return loop.run_until_complete(make())


def test_sqlite_delivers_after_commit_and_never_after_rollback(tmp_path, loop):
    engine = create_engine(f"sqlite:///{tmp_path / 'events.db'}")
    sub = _subscribe(loop, frozenset({41}))
    try:
        with Session(engine) as s:
            publish(s, Event("suggestion.changed", 41, {"suggestion_id": 1}))
            s.execute(text("SELECT 1"))
            s.rollback()
            publish(s, Event("session.stored", 41, {"session_id": 2}))
            assert sub.queue.empty(), "nothing before the commit"
            s.commit()
        assert [e.kind for e in _received(sub, timeout=1.0)] == ["session.stored"]
    finally:
        HUB.unsubscribe(sub)
        engine.dispose()


@pytest.mark.skipif(not PG_URL.startswith("postgresql"), reason="LISTEN/NOTIFY: the PostgreSQL run of the suite")
def test_postgresql_carries_events_to_another_connection_at_commit(loop):
    engine = create_engine(PG_URL)
    listener = Listener(engine.url).start()
    sub = _subscribe(loop, frozenset({424242}))
    try:
        assert listener.ready.wait(10), "the listener did not LISTEN within 10 s"
        with Session(engine) as s:
            publish(s, Event("plan.changed", 424242, {"plan_id": 9}))
            s.execute(text("SELECT 1"))
            s.rollback()  # a rolled-back change sends nothing
            publish(s, Event("session.stored", 424242, {"session_id": 5}))
            s.execute(text("SELECT 1"))
            s.commit()
        got = _received(sub)
        assert [(e.kind, e.data) for e in got] == [("session.stored", {"session_id": 5})]
    finally:
        HUB.unsubscribe(sub)
        listener.stop()
        engine.dispose()


def test_conninfo_keeps_the_query_and_drops_the_driver():
    engine = create_engine("postgresql+psycopg://u:p@db:5432/coach?options=-csearch_path%3Dx")
    assert conninfo(engine.url) == "postgresql://u:p@db:5432/coach?options=-csearch_path%3Dx"
