"""A full disk at home: recognising it, and writing a session again and again until there is room.

The frames of a set are in memory when its file is written; a full disk must not lose them, nor end the program
with a traceback. The writer says in plain words that the disk is full and that the session waits in memory, then
tries again every RETRY_S seconds until the write succeeds (space was freed) or the program is stopped.
"""

from __future__ import annotations

import errno
import time
from collections.abc import Callable
from typing import TypeVar

T = TypeVar("T")
RETRY_S = 10.0  # seconds between two tries to write a session while the disk is full
DISK_FULL = frozenset({errno.ENOSPC, errno.EDQUOT})


def is_disk_full(exc: BaseException) -> bool:
    """True for an OSError that says the disk (or the user's quota on it) is full."""
    return isinstance(exc, OSError) and exc.errno in DISK_FULL


def plain_words(exc: OSError) -> str:
    """Returns what a full disk means for the family, naming the file that could not be written."""
    where = f" (writing {exc.filename})" if exc.filename else ""
    return f"The disk of this computer is full{where}. Free some space, e.g. by deleting files you no longer need."


def write_when_space(write: Callable[[], T], *, what: str, say: Callable[[str], None]) -> T:
    """Returns write()'s result; while it fails because the disk is full, says once (through say) that `what` is
    kept in memory and tries again every RETRY_S seconds. Any other error is raised at once."""
    told = False
    while True:
        try:
            return write()
        except OSError as exc:
            if not is_disk_full(exc):
                raise
            if not told:
                say(f"{plain_words(exc)} {what} is kept in memory and saved as soon as there is room (trying "
                    f"again every {RETRY_S:g} s); do not switch the computer off or close this program.")  # fmt: skip
                told = True
        time.sleep(RETRY_S)
