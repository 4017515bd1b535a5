"""Login and pairing throttling that holds against a hostile client: attempts are counted before the password is
checked (so parallel guesses count too), per account and address, per address over all accounts and per account over
all addresses; pairing codes have an attempt limit; password hashing has a cap per process."""

from __future__ import annotations

import threading
import time

import pytest
from sqlalchemy import delete, select
from sqlalchemy.orm import Session

from backend import security
from backend.config import Settings
from backend.exceptions import NotAuthenticated, PasswordCheckBusy, TooManyLoginAttempts
from backend.users import service
from backend.users.models import LoginAttempt, User
from tests.backend.conftest import PASSWORD

WRONG = "not the password"


@pytest.fixture
def committed_user(engine):
    """A user committed for real, so that separate transactions see it; deleted with the attempts afterwards."""
    if engine.dialect.name == "sqlite" and engine.url.database in (None, "", ":memory:"):
        pytest.skip("concurrent writers need a database file")
    email = "throttle-parallel@example.org"
    with Session(engine) as s, s.begin():
        s.add(User(email=email, role="patient", password_hash=security.hash_password(PASSWORD)))
    yield email
    with Session(engine) as s, s.begin():
        s.execute(delete(LoginAttempt).where(LoginAttempt.email == email))
        s.execute(delete(User).where(User.email == email))


def test_thirty_parallel_wrong_logins_check_at_most_five_passwords(engine, committed_user, monkeypatch):
    settings = Settings(LOGIN_MAX_FAILURES=5)
    checked, lock = [], threading.Lock()
    real_verify = security.verify_password

    def slow_verify(password_hash, password):  # argon2 takes ~0.5 s: every request is in flight at once
        with lock:
            checked.append(password)
        time.sleep(0.3)
        return real_verify(password_hash, password)

    monkeypatch.setattr(service, "verify_password", slow_verify)
    outcomes: list[str] = []
    start = threading.Barrier(30, timeout=30)

    def attempt() -> None:
        start.wait()
        with Session(engine, expire_on_commit=False) as s:
            try:
                service.login(db_session=s, settings=settings, email=committed_user, password=WRONG, ip="10.9.9.9")
                outcome = "in"
            except TooManyLoginAttempts:
                outcome = "throttled"
            except Exception as exc:  # noqa: BLE001 - a wrong password or a busy database is an answer too
                outcome = type(exc).__name__
                s.rollback()
        with lock:
            outcomes.append(outcome)

    threads = [threading.Thread(target=attempt) for _ in range(30)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    assert len(outcomes) == 30 and "in" not in outcomes
    assert len(checked) <= 5, f"{len(checked)} passwords were checked; the limit is 5"
    assert outcomes.count("throttled") >= 25, outcomes


def test_one_password_on_many_accounts_is_throttled_per_address(client, make_user, db_session):
    settings = Settings(LOGIN_MAX_FAILURES_PER_IP=20)
    users = [make_user("patient", password=PASSWORD) for _ in range(21)]
    for user in users[:20]:  # one guess each: no account sees more than one failure
        with pytest.raises(Exception, match="wrong e-mail or password"):
            service.login(db_session=db_session, settings=settings, email=user.email, password=WRONG, ip="10.1.1.1")
    with pytest.raises(TooManyLoginAttempts, match="from this address") as refused:
        service.login(db_session=db_session, settings=settings, email=users[20].email, password=PASSWORD,
                      ip="10.1.1.1")  # fmt: skip
    assert 0 < int(refused.value.headers["Retry-After"]) <= 15 * 60
    # another address is not held back by it
    service.login(db_session=db_session, settings=settings, email=users[20].email, password=PASSWORD, ip="10.2.2.2")


def test_one_account_guessed_from_many_addresses_is_throttled(make_user, db_session):
    settings = Settings(LOGIN_MAX_FAILURES_PER_ACCOUNT=30)
    user = make_user("therapist", password=PASSWORD)
    for i in range(30):
        with pytest.raises(Exception, match="wrong e-mail or password"):
            service.login(db_session=db_session, settings=settings, email=user.email, password=WRONG,
                          ip=f"10.3.0.{i}")  # fmt: skip
    with pytest.raises(TooManyLoginAttempts, match="this account"):
        service.login(db_session=db_session, settings=settings, email=user.email, password=PASSWORD, ip="10.4.0.1")


def test_a_guess_from_many_addresses_does_not_lock_the_owner_out_at_home(make_user, db_session):
    """Anyone who knows a therapist's e-mail could otherwise keep them out: 30 wrong passwords per 15 minutes."""
    settings = Settings(LOGIN_MAX_FAILURES_PER_ACCOUNT=30)
    user = make_user("therapist", password=PASSWORD)
    service.login(db_session=db_session, settings=settings, email=user.email, password=PASSWORD, ip="10.6.0.1")
    for i in range(31):
        with pytest.raises((TooManyLoginAttempts, NotAuthenticated)):
            service.login(db_session=db_session, settings=settings, email=user.email, password=WRONG,
                          ip=f"10.7.0.{i}")  # fmt: skip
    _, login_session, _ = service.login(db_session=db_session, settings=settings, email=user.email,
                                        password=PASSWORD, ip="10.6.0.1")  # fmt: skip
    assert login_session.user_id == user.id  # the address the owner signed in from before still lets them in
    with pytest.raises(TooManyLoginAttempts, match="this account"):  # a new address is still held back
        service.login(db_session=db_session, settings=settings, email=user.email, password=PASSWORD, ip="10.8.0.1")


def test_a_known_address_still_has_its_own_limit(make_user, db_session):
    settings = Settings()
    user = make_user("therapist", password=PASSWORD)
    service.login(db_session=db_session, settings=settings, email=user.email, password=PASSWORD, ip="10.9.0.1")
    for _ in range(settings.LOGIN_MAX_FAILURES):
        with pytest.raises(NotAuthenticated):
            service.login(db_session=db_session, settings=settings, email=user.email, password=WRONG, ip="10.9.0.1")
    with pytest.raises(TooManyLoginAttempts, match="from this address"):
        service.login(db_session=db_session, settings=settings, email=user.email, password=WRONG, ip="10.9.0.1")


def test_a_refused_attempt_is_not_counted_as_a_failure(make_user, db_session):
    settings = Settings()
    user = make_user("patient", password=PASSWORD)
    for _ in range(settings.LOGIN_MAX_FAILURES + 3):
        with pytest.raises((TooManyLoginAttempts, Exception)):
            service.login(db_session=db_session, settings=settings, email=user.email, password=WRONG, ip="10.5.0.1")
    rows = db_session.scalars(select(LoginAttempt).where(LoginAttempt.email == user.email)).all()
    assert len(rows) == settings.LOGIN_MAX_FAILURES  # the throttled ones checked nothing and left no row


def test_pairing_codes_have_an_attempt_limit(client, make_patient_with_therapist, auth_headers, db_session):
    patient, _ = make_patient_with_therapist()
    code = client.post(f"/api/v1/patients/{patient.id}/pairing-codes", headers=auth_headers(patient)).json()["code"]
    db_session.commit()
    limit = Settings().PAIRING_MAX_FAILURES
    for _ in range(limit):
        r = client.post("/api/v1/devices/pair", json={"code": security.new_pairing_code(), "name": "guess"})
        assert r.status_code == 403, r.text
    r = client.post("/api/v1/devices/pair", json={"code": code, "name": "home"})
    assert r.status_code == 429 and r.json()["error"] == "TooManyLoginAttempts", r.text
    assert "pairing" in r.json()["detail"] and int(r.headers["Retry-After"]) > 0


def test_password_hashing_is_capped_per_process(monkeypatch):
    monkeypatch.setattr(security, "HASH_WAIT_S", 0.2)
    release = threading.Event()
    holders = [threading.Thread(target=lambda: security.with_hash_slot(release.wait))
               for _ in range(security.MAX_CONCURRENT_HASHES)]  # fmt: skip
    for t in holders:
        t.start()
    time.sleep(0.1)
    try:
        with pytest.raises(PasswordCheckBusy) as busy:
            security.verify_password(None, "anything")
        assert busy.value.status_code == 503 and busy.value.headers["Retry-After"]
    finally:
        release.set()
        for t in holders:
            t.join()
    assert security.verify_password(None, "anything") is False  # slots come back
