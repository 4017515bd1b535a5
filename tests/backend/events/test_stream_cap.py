"""One user cannot hold more than MAX_STREAMS_PER_USER event streams open on a server process (429)."""

from __future__ import annotations

import asyncio

import pytest

from backend.events.hub import MAX_STREAMS_PER_USER, Hub, TooManyStreams


def test_a_user_gets_at_most_the_cap_of_open_streams():
    async def run():
        hub = Hub()
        mine = [hub.subscribe(None, user_id=3) for _ in range(MAX_STREAMS_PER_USER)]
        with pytest.raises(TooManyStreams) as refused:
            hub.subscribe(None, user_id=3)
        assert refused.value.status_code == 429
        hub.subscribe(None, user_id=4)  # another user has their own
        for _ in range(3 * MAX_STREAMS_PER_USER):  # a stream of no user (the home agent's command stream)
            hub.subscribe(frozenset({1}))
        hub.unsubscribe(mine[0])
        hub.subscribe(None, user_id=3)  # a closed stream frees its place
        return hub.count()

    assert asyncio.run(run()) == MAX_STREAMS_PER_USER + 1 + 3 * MAX_STREAMS_PER_USER
