"""The home agent as a library: the one public entry for programs that run agents themselves (the server's demo
clinic, test harnesses), so that they do not reach into the agent's command modules, queue and uploader.

    agent = HomeAgent.load(home)  or  HomeAgent.pair(server_url, code, name=..., home=home)
    agent.recover()                                  # what a start does: queue sets a crash interrupted
    agent.record_simulated("squat", reps=8, seed=1, started="2026-11-20T10:00:00Z", session_id=...)
    report = agent.upload()                          # one pass over the disk queue

Errors: ConfigError (not paired, or a broken configuration) and AgentError (pairing refused, ...), both AgentError.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

from kinect_agent.capture import capture, queue_session
from kinect_agent.config import AgentConfig, ConfigError, load_config, normalize_server_url, save_config
from kinect_agent.errors import AgentError
from kinect_agent.pairing import pair as _pair
from kinect_agent.queue import SessionQueue
from kinect_agent.upload import DrainReport, RetryPolicy, Uploader, drain

__all__ = ["AgentConfig", "AgentError", "ConfigError", "DrainReport", "HomeAgent"]


@dataclass
class HomeAgent:
    """One paired home agent: its configuration (server, device token, pairing) and its disk queue."""

    config: AgentConfig

    @classmethod
    def load(cls, home: str | Path) -> HomeAgent:
        """Returns the agent paired in the home folder; raises ConfigError when it is not paired."""
        return cls(load_config(home))

    @classmethod
    def pair(cls, server_url: str, code: str, *, name: str, home: str | Path) -> HomeAgent:
        """Pairs a new agent in the home folder with a pairing code (replacing an earlier pairing there)."""
        return cls(_pair(server_url, code, name=name, home=home, force=True))

    def moved(self, server_url: str, home: str | Path) -> HomeAgent:
        """Returns this agent with its server's new address saved in the home folder (the same server, reached at
        another port or name): its pairing, and so the sets in its queue, stay valid there."""
        config = replace(self.config, server_url=normalize_server_url(server_url))
        save_config(config, home)
        return HomeAgent(config)

    @property
    def queue(self) -> SessionQueue:
        return SessionQueue(self.config.queue_dir)

    def recover(self) -> None:
        """Queues the raw copies of sets a stopped agent left behind and removes temporary files, as a start does."""
        queue = self.queue
        queue.recover_held()
        queue.clean_partial()

    def where(self, session_id: str) -> str | None:
        """Returns where a session is: "captured", "pending", "sent", "rejected", "held", or None."""
        return self.queue.where(session_id)

    def record_simulated(self, exercise: str, *, reps: int, seed: int, started: str | None = None,
                         session_id: str | None = None) -> str:  # fmt: skip
        """Simulates a set, filters and queues it (bound to this pairing) as a recorded one would be; returns its
        session id. started: ISO 8601 UTC of its first frame (None: it ends now)."""
        rec = capture("simulator", exercise=exercise, reps=reps, seed=seed)
        return queue_session(self.queue, rec, created_at=started, session_id=session_id,
                             recorded_by=self.config.recorded_by).stem  # fmt: skip

    def upload(self, *, attempts: int = 3, base_delay_s: float = 1.0, server_url: str | None = None) -> DrainReport:
        """Uploads the queue once (oldest first, idempotent) and returns what happened to each file. server_url:
        another address of the same server (a proxy) instead of the paired one."""
        policy = RetryPolicy(max_attempts=attempts, base_delay_s=base_delay_s)
        with Uploader(server_url or self.config.server_url, self.config.device_token, policy=policy) as uploader:
            return drain(self.queue, uploader)
