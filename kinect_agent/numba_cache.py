"""Where numba keeps the agent's compiled kernels on disk when numba's own places are not writable.

numba caches a `cache=True` kernel in $NUMBA_CACHE_DIR when set, else in `__pycache__` beside its module when the
user running it can write there, else in that user's cache folder (`~/.cache/numba` on Linux). When none is writable
(the agent installed read-only, system-wide or in a root-owned venv, and run by a service user without a home
folder), numba refuses to define the kernel ("cannot cache function ...: no locator available") and every command
that filters fails at import. cache_for() then points numba at the agent's home folder, `$KINECT_AGENT_HOME/numba`
(the service writes its queue there), else at `<temporary folder>/kinect-agent-numba-<user>` (emptied when the
computer restarts); with neither, the kernels compile in each process and are not cached.
"""

from __future__ import annotations

import functools
import os
import stat
import sys
import tempfile
from pathlib import Path
from typing import Any, cast

try:
    import numba as numba  # the kernels' compiler, for every kernel module (None where it is not installed)
except ImportError:  # pragma: no cover - exercised only where numba is absent
    numba = None  # type: ignore[assignment]

ENV_HOME = "KINECT_AGENT_HOME"  # the agent's home folder (kinect_agent.config.ENV_HOME)
TEMPORARY_PREFIX = "kinect-agent-numba-"


def cache_for(module_file: str) -> bool:
    """Returns the `cache` option of the numba kernels defined in module_file: True when numba has, or is now given
    (numba.config.CACHE_DIR, see fallback_folders), a writable folder for them; False (compile in each process) with
    one line on stderr when there is none."""
    if _numba_finds_a_folder(module_file):
        return True
    return _use_fallback()


def fallback_folders() -> list[Path]:
    """Returns the folders tried, in order, when numba has no writable folder of its own: the agent's home folder's
    `numba` ($KINECT_AGENT_HOME, when set), then the temporary folder's `kinect-agent-numba-<user id>`."""
    folders = [Path(os.environ[ENV_HOME]) / "numba"] if os.environ.get(ENV_HOME) else []
    user = str(os.getuid()) if hasattr(os, "getuid") else os.environ.get("USERNAME", "user")
    return [*folders, Path(tempfile.gettempdir()) / f"{TEMPORARY_PREFIX}{user}"]


def _numba_finds_a_folder(module_file: str) -> bool:
    """Tells whether one of numba's cache locators (its order, as numba.core.caching.CacheImpl tries them) has a
    writable folder for the kernels of module_file."""
    from numba.core.caching import CacheImpl

    if cast(Any, numba.config).CACHE_LOCATOR_CLASSES:  # $NUMBA_CACHE_LOCATOR_CLASSES: the user chose numba's places
        return True
    locators: list[Any] = list(CacheImpl._locator_classes)
    return any(cls.from_function(cache_for, module_file) is not None for cls in locators)


@functools.cache
def _use_fallback() -> bool:
    """Points numba's cache at the first of fallback_folders that is this user's own and writable; returns whether
    one was (said once per process on stderr when none was)."""
    for folder in fallback_folders():
        if _own_writable_folder(folder):
            cast(Any, numba.config).CACHE_DIR = str(folder)  # read when a kernel's cache is located
            return True
    tried = ", ".join(str(folder) for folder in fallback_folders())
    print(f"numba's cache: no writable folder (install folder, home folder, {tried}): the filter is compiled in each "
          f"process; set {ENV_HOME} or NUMBA_CACHE_DIR to a folder this user can write", file=sys.stderr)  # fmt: skip
    return False


def _own_writable_folder(folder: Path) -> bool:
    """Makes folder (this user's only) when missing; tells whether it is a real folder owned by this user, writable
    by no one else (numba's cache holds pickled code: another user's files must not be loaded), and writable."""
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        found = folder.lstat()
        if not stat.S_ISDIR(found.st_mode) or found.st_mode & (stat.S_IWGRP | stat.S_IWOTH):
            return False
        if hasattr(os, "getuid") and found.st_uid != os.getuid():
            return False
        tempfile.TemporaryFile(dir=folder).close()
    except OSError:
        return False
    return True
