"""Secrets: argon2id password hashes, high-entropy bearer tokens (stored as sha256), pairing codes."""

from __future__ import annotations

import hashlib
import hmac
import secrets
import threading
from collections.abc import Callable
from typing import TypeVar

from argon2 import PasswordHasher
from argon2.exceptions import InvalidHashError, VerificationError

from backend.exceptions import PasswordCheckBusy

API_TOKEN_PREFIX = "khc_"  # personal API tokens
DEVICE_TOKEN_PREFIX = "khd_"  # home-device tokens
SESSION_TOKEN_PREFIX = "khs_"  # browser login cookie
PAIRING_ALPHABET = "ABCDEFGHJKLMNPQRSTUVWXYZ23456789"  # no 0/O, 1/I
PAIRING_CODE_LENGTH = 8

# An argon2id hash costs about 0.5 s of one core and 64 MiB: at most this many at once per server process, so that
# a flood of logins (even unthrottled ones: every address and e-mail new) cannot take every core from the others.
MAX_CONCURRENT_HASHES = 2
HASH_WAIT_S = 10.0  # a request waits this long for a slot, then gets 503 PasswordCheckBusy with Retry-After

PASSWORD_HASHER = PasswordHasher()  # argon2id, the library's recommended parameters (tests/backend/test_security.py)
DUMMY_HASH = PASSWORD_HASHER.hash("not-a-real-password")  # checked when there is no user, so that it takes as long
_hash_slots = threading.BoundedSemaphore(MAX_CONCURRENT_HASHES)
T = TypeVar("T")


def with_hash_slot(work: Callable[[], T]) -> T:
    """Returns work() run in one of the process's password-hashing slots; raises PasswordCheckBusy when none
    frees up within HASH_WAIT_S."""
    if not _hash_slots.acquire(timeout=HASH_WAIT_S):
        raise PasswordCheckBusy(
            "the server is checking many passwords at once; retry in a few seconds", headers={"Retry-After": "5"}
        )
    try:
        return work()
    finally:
        _hash_slots.release()


def hash_password(password: str) -> str:
    """Returns the argon2id hash of a password."""
    return with_hash_slot(lambda: PASSWORD_HASHER.hash(password))


def verify_password(password_hash: str | None, password: str) -> bool:
    """Returns whether password matches the hash (spends the same time when there is no hash)."""

    def check() -> bool:
        try:
            return PASSWORD_HASHER.verify(password_hash or DUMMY_HASH, password) and password_hash is not None
        except (VerificationError, InvalidHashError):
            return False

    return with_hash_slot(check)


def new_token(prefix: str) -> str:
    """Returns a new bearer token: prefix + 43 url-safe characters (256 bits)."""
    return prefix + secrets.token_urlsafe(32)


def token_hash(token: str) -> str:
    """Returns the sha256 hex digest under which a token or code is stored."""
    return hashlib.sha256(token.encode()).hexdigest()


def new_pairing_code() -> str:
    """Returns a short human-typable pairing code such as 'K7QF-M2XA' (40 bits)."""
    raw = "".join(secrets.choice(PAIRING_ALPHABET) for _ in range(PAIRING_CODE_LENGTH))
    return raw[:4] + "-" + raw[4:]


def normalize_pairing_code(code: str) -> str:
    """Returns the canonical form of a typed pairing code (upper case, one dash, spaces removed)."""
    raw = "".join(ch for ch in code.upper() if ch.isalnum())
    return raw[:4] + "-" + raw[4:]


def new_csrf_secret() -> str:
    """Returns a new CSRF token for a login session."""
    return secrets.token_urlsafe(32)


def same_secret(a: str, b: str) -> bool:
    """Returns whether two secrets are equal, in constant time."""
    return hmac.compare_digest(a.encode(), b.encode())
