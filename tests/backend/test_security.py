"""Password hashing: the product hashes with argon2id at the library's recommended parameters; the suite's cheap
hasher (tests/backend/conftest.py) differs from it in cost only."""

from __future__ import annotations

import json
import subprocess
import sys

import argon2

from backend import security
from tests.backend.conftest import PASSWORD
from tests.conftest import REPO

# run in a fresh interpreter, as the server starts (no test fixture): the hasher's parameters, then those read back
# from its dummy hash and from a new hash, each as [type, time_cost, memory_cost KiB, parallelism, hash_len, salt_len]
PRODUCT_PARAMETERS = """
import json
import argon2
from backend import security
def listed(p):
    return [p.type.name, p.time_cost, p.memory_cost, p.parallelism, p.hash_len, p.salt_len]
print(json.dumps({"hasher": listed(security.PASSWORD_HASHER),
                  "dummy hash": listed(argon2.extract_parameters(security.DUMMY_HASH)),
                  "new hash": listed(argon2.extract_parameters(security.hash_password("a password")))}))
"""


def test_the_product_hashes_with_the_librarys_recommended_parameters() -> None:
    run = subprocess.run([sys.executable, "-c", PRODUCT_PARAMETERS], cwd=REPO, capture_output=True, text=True,
                         timeout=120)  # fmt: skip
    assert run.returncode == 0, run.stderr
    r = argon2.profiles.get_default_parameters()
    assert r.type is argon2.Type.ID and r.memory_cost >= 19 * 1024  # what the library recommends is still argon2id
    recommended = [r.type.name, r.time_cost, r.memory_cost, r.parallelism, r.hash_len, r.salt_len]
    assert json.loads(run.stdout) == dict.fromkeys(("hasher", "dummy hash", "new hash"), recommended), run.stdout


def test_the_suites_hashes_are_argon2id_in_the_products_format_only_cheaper() -> None:
    made = security.hash_password(PASSWORD)
    suite, recommended = argon2.extract_parameters(made), argon2.profiles.get_default_parameters()
    assert (suite.type, suite.version, suite.hash_len, suite.salt_len) == (
        recommended.type, recommended.version, recommended.hash_len, recommended.salt_len)  # fmt: skip
    assert (suite.time_cost, suite.memory_cost, suite.parallelism) == (1, 1024, 1), suite  # the conftest's hasher
    assert security.verify_password(made, PASSWORD) and not security.verify_password(made, "not " + PASSWORD)
    assert argon2.extract_parameters(security.DUMMY_HASH) == suite  # a login without a user costs what one with does
