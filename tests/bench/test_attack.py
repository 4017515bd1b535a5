"""bench/attack.py case generation (no database): every family yields cases, seeds make different and
reproducible cases, the fixed catalogue DEFECTS is used, and the files the attacks start from are valid."""

from collections import Counter

import pytest

from backend.config import Settings
from bench.attack import FAMILIES, Context, attack_cases, base_file, defect_cases
from kinect_agent.formats import session_file as sf
from tests.backend.khs_files import DEFECTS


@pytest.fixture(scope="module")
def ctx(tmp_path_factory) -> Context:
    """Ids as the run would have them, the server's default limits, bombs cached in a temp folder."""
    fields = Settings.model_fields
    cache = tmp_path_factory.mktemp("attack-cache")
    return Context(3, 1, 4, 2, fields["MAX_UPLOAD_BYTES"].default, fields["SESSION_MAX_FRAMES"].default, cache)


@pytest.fixture(scope="module")
def seed_0(ctx):
    return attack_cases(0, ctx)


def _fingerprints(cases, family=None) -> set[str]:
    return {c.fingerprint() for c in cases if family is None or c.family == family}


def test_defects_catalogue_is_the_fixed_family(ctx) -> None:
    assert len(DEFECTS) >= 20
    cases = defect_cases(ctx)
    assert sorted(c.name for c in cases) == sorted(DEFECTS)
    assert all(c.family == "defects" and c.expect for c in cases)


def test_every_family_yields_several_cases(seed_0) -> None:
    counts = Counter(c.family for c in seed_0)
    assert set(counts) == set(FAMILIES) - {"defects"}
    assert min(counts.values()) >= 3, counts
    assert all(c.seed == 0 for c in seed_0)
    for family in counts:  # names say which case it is: unique within a family and seed
        names = [c.name for c in seed_0 if c.family == family]
        assert len(names) == len(set(names)), family


def test_cases_differ_between_seeds_and_repeat_for_a_seed(ctx, seed_0) -> None:
    seed_1 = attack_cases(1, ctx)
    for family in set(FAMILIES) - {"defects"}:
        assert _fingerprints(seed_0, family) != _fingerprints(seed_1, family), family
    assert _fingerprints(attack_cases(0, ctx)) == _fingerprints(seed_0)


def test_quick_makes_fewer_random_cases(ctx, seed_0) -> None:
    quick = attack_cases(0, ctx, quick=True)
    assert set(c.family for c in quick) == set(c.family for c in seed_0)
    assert len(quick) < len(seed_0)


def test_attacks_start_from_a_valid_file_with_equal_recordings() -> None:
    payload = sf.decode(base_file(0))
    assert payload.filtered is not None
    assert payload.filtered.n_frames == payload.raw.n_frames  # times are replaced in both recordings alike


def test_wrong_owner_files_are_recorded_by_a_and_sent_by_b(ctx, seed_0) -> None:
    owner = [c for c in seed_0 if c.family == "wrong_owner"]
    assert all(c.device == "B" for c in owner)
    assert sf.decode(owner[0].body).recorded_by == {"device_id": ctx.device_a, "patient_id": ctx.patient_a}


def test_oversized_bodies_exceed_the_limit(ctx, seed_0) -> None:
    for case in (c for c in seed_0 if c.family == "oversized_body"):
        body = case.body() if callable(case.body) else case.body
        size = len(body) if isinstance(body, bytes) else sum(len(part) for part in body)
        declared = int(case.headers.get("Content-Length", size))
        assert max(size, declared) > ctx.max_upload_bytes, case.name
