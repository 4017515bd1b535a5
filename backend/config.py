"""Server configuration: one pydantic-settings class read from COACH_* environment variables."""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path
from typing import Literal
from urllib.parse import urlsplit

from pydantic import Field, model_validator
from pydantic_settings import BaseSettings, SettingsConfigDict


class Settings(BaseSettings):
    """Holds every setting of the coaching server. It needs no secret of its own: login sessions, CSRF secrets,
    API and device tokens are random values kept in the database (tokens as SHA-256 hashes)."""

    model_config = SettingsConfigDict(env_prefix="COACH_", case_sensitive=True, extra="ignore")

    ENVIRONMENT: Literal["local", "staging", "production"] = "local"
    DATABASE_URL: str = "sqlite:///./var/coach.db"
    HOST: str = "127.0.0.1"
    PORT: int = 8000
    WORKERS: int = Field(default=1, ge=1, le=64)  # uvicorn worker processes of `coach-server serve`
    # proxies whose X-Forwarded-For `coach-server serve` believes (comma-separated addresses or networks): only yours
    FORWARDED_ALLOW_IPS: str = "127.0.0.1"
    LOGIN_SESSION_HOURS: float = 12.0
    # failed logins within LOGIN_WINDOW_MINUTES before the next is refused (429): per account from one address, per
    # address over all accounts (one password tried on many), per account over all addresses (a spread-out guess)
    LOGIN_MAX_FAILURES: int = Field(default=5, ge=1)
    LOGIN_MAX_FAILURES_PER_IP: int = Field(default=20, ge=1)
    LOGIN_MAX_FAILURES_PER_ACCOUNT: int = Field(default=30, ge=1)
    LOGIN_WINDOW_MINUTES: float = Field(default=15.0, gt=0)
    PAIRING_CODE_MINUTES: float = 15.0
    PAIRING_MAX_FAILURES: int = Field(default=10, ge=1)  # wrong pairing codes per address within the login window
    # session uploads: ~116 B/frame (raw + filtered) measured on simulated sets, so 32 MiB holds two hours at 30 Hz
    MAX_UPLOAD_BYTES: int = 32 * 1024 * 1024
    MAX_JSON_BYTES: int = Field(default=1024 * 1024, ge=1024)  # any other request body (JSON): 413 above it
    SESSION_MAX_FRAMES: int = 2 * 30 * 60 * 60  # per recording: two hours at 30 Hz (analysis of the most: ~1.5 s)
    SESSION_MAX_DECODED_BYTES: int = 128 * 1024 * 1024  # all recordings of one file, after decompression (268 B/frame)
    # per recording: no home session lasts longer; with the frame limit it bounds the work one upload can cause
    SESSION_MAX_DURATION_S: float = Field(default=2 * 60 * 60.0, gt=0)
    # a download (csv, trc, bvh, fhir) is built in the request only for a recording within both limits (≤ 2 s CPU,
    # ≤ 256 MiB measured at them, bench/README.md); any larger one by a worker, then read from the object store
    EXPORT_DIRECT_MAX_FRAMES: int = Field(default=9000, ge=0)
    EXPORT_DIRECT_MAX_S: float = Field(default=300.0, ge=0)
    CHECK_MIGRATIONS: bool = True
    # ready the camera sets' live filter in a background thread at start-up (its compiled code: ~1 s from numba's
    # cache, half a minute or more the first time); off: the first camera set's first batch waits for it
    LIVE_WARM_UP: bool = True
    COOKIE_SECURE: bool | None = None  # None: secure when PUBLIC_URL is https, or ENVIRONMENT is not local
    # where people reach the app, e.g. https://coach.example.org/clinic behind a reverse proxy; its path is the
    # prefix of every URL the pages build (never taken from a request's Host header); empty: served at /
    PUBLIC_URL: str = ""
    # an event stream (GET /api/v1/events) ends after this long and the browser reconnects, checking its login again
    EVENTS_STREAM_MAX_S: float = Field(default=300.0, ge=0.0)
    DB_SLOT_WAIT_S: float = Field(default=30.0, gt=0.0)  # a request waits this long for a database slot, then 503
    LIVE_OFFLINE_GRACE_S: float = Field(default=2.0, ge=0.0, le=60.0)  # a home agent's reconnection is no "offline"
    # session files and replays (backend/storage): "local" files under STORAGE_DIR, or an S3-compatible bucket
    STORAGE_BACKEND: Literal["local", "s3"] = "local"
    STORAGE_DIR: str = ""  # empty: "objects" beside the SQLite database file, else ./var/objects
    S3_BUCKET: str = ""
    S3_PREFIX: str = ""  # keys go under this folder of the bucket
    S3_ENDPOINT_URL: str = ""  # e.g. http://minio:9000; empty: AWS S3
    S3_REGION: str = "us-east-1"
    S3_ACCESS_KEY_ID: str = ""  # empty: boto3's usual chain (AWS_* variables, instance role …)
    S3_SECRET_ACCESS_KEY: str = ""
    # session files older than this many days are removed by `coach-server retention` (metrics kept); 0: off
    RETENTION_DAYS: int = Field(default=0, ge=0)
    # reminder e-mails (backend/reminders): sent through this SMTP server; empty SMTP_HOST: no e-mails are sent
    SMTP_HOST: str = ""
    SMTP_PORT: int = Field(default=587, ge=1, le=65535)
    SMTP_USER: str = ""  # empty: no SMTP login
    SMTP_PASSWORD: str = ""
    SMTP_FROM: str = ""  # the From address of reminder e-mails, e.g. "Home Coach <coach@clinic.example.org>"
    SMTP_STARTTLS: bool = True  # upgrade the connection with STARTTLS before logging in and sending
    SMTP_TIMEOUT_S: float = Field(default=20.0, gt=0)  # per SMTP connection
    TIME_ZONE: str = "UTC"  # IANA time zone of patients who have none of their own (their reminder times)
    REMINDER_CHECK_S: float = Field(default=60.0, gt=0)  # how often each server process looks for due reminders
    REMINDER_LATE_MINUTES: float = Field(default=60.0, gt=0)  # a reminder not sent this long after its time is dropped
    # run queued jobs (replay builds, re-analysis, abandoned camera sets) in a thread of each server process too:
    # for the demo and a one-process install without `coach-server worker`
    EMBEDDED_WORKER: bool = False
    # a camera set whose page sent nothing for this long (closed for good) is ended by a job-queue worker: stored
    # once when its buffered landmarks make a session, else marked failed; its landmark batches are deleted
    CAMERA_SET_IDLE_HOURS: float = Field(default=24.0, gt=0)
    CAMERA_SWEEP_S: float = Field(default=600.0, gt=0)  # how often each worker looks for such sets

    @model_validator(mode="after")
    def _check_public_url(self) -> Settings:
        if self.PUBLIC_URL:
            url = urlsplit(self.PUBLIC_URL)
            if url.scheme not in ("http", "https") or not url.netloc or url.query or url.fragment:
                raise ValueError(
                    f"COACH_PUBLIC_URL must be an http(s) URL such as https://coach.example.org/clinic, "
                    f"without query or fragment; got {self.PUBLIC_URL!r}"
                )
        return self

    @model_validator(mode="after")
    def _check_storage(self) -> Settings:
        if self.STORAGE_BACKEND == "s3" and not self.S3_BUCKET:
            raise ValueError("COACH_STORAGE_BACKEND=s3 needs COACH_S3_BUCKET (the bucket session files go to)")
        return self

    @model_validator(mode="after")
    def _check_reminders(self) -> Settings:
        from backend.reminders.times import zone

        zone(self.TIME_ZONE)  # ValueError naming the zone
        if self.SMTP_HOST and not (self.SMTP_FROM and self.PUBLIC_URL):
            raise ValueError(
                "COACH_SMTP_HOST needs COACH_SMTP_FROM (the sender of reminder e-mails) and COACH_PUBLIC_URL (where "
                "the e-mail's unsubscribe link points)"
            )
        return self

    @property
    def reminder_emails(self) -> bool:
        """Returns whether reminder e-mails are sent (an SMTP server is configured)."""
        return bool(self.SMTP_HOST)

    @property
    def storage_dir(self) -> str:
        """Returns the folder of the local object store: STORAGE_DIR, else "objects" in the server's data folder
        (beside the SQLite database file), else ./var/objects."""
        if self.STORAGE_DIR:
            return self.STORAGE_DIR
        url = self.DATABASE_URL
        if url.startswith("sqlite:///") and url not in ("sqlite:///", "sqlite:///:memory:"):
            path = url.removeprefix("sqlite:///").split("?", 1)[0]
            return str(Path(path).parent / "objects")
        return "./var/objects"

    @property
    def root_path(self) -> str:
        """Returns the path prefix of the app's URLs ('' or e.g. '/clinic'), from PUBLIC_URL."""
        return urlsplit(self.PUBLIC_URL).path.rstrip("/") if self.PUBLIC_URL else ""

    @property
    def public_https(self) -> bool:
        """Returns whether people reach the app over HTTPS (PUBLIC_URL is https)."""
        return urlsplit(self.PUBLIC_URL).scheme == "https"

    @property
    def hsts(self) -> bool:
        """Returns whether answers carry Strict-Transport-Security: the public URL is https on a host name other than
        the loopback's (a browser would keep http://localhost from every other local server for a year)."""
        return self.public_https and urlsplit(self.PUBLIC_URL).hostname not in ("localhost", "127.0.0.1", "::1")

    @property
    def cookie_secure(self) -> bool:
        """Returns whether the login cookie carries the Secure flag (COOKIE_SECURE, else on when the public URL is
        https or outside local development)."""
        if self.COOKIE_SECURE is not None:
            return self.COOKIE_SECURE
        return self.public_https or self.ENVIRONMENT != "local"


@lru_cache
def get_settings() -> Settings:
    """Returns the process-wide settings (read once from the environment)."""
    return Settings()
