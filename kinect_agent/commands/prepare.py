"""`kinect-agent prepare`: compile the filter's numba kernels into numba's on-disk cache, once after an install.

`kinect-agent pair` does the same after pairing; run this as the user who runs the agent (the cache it fills is the
one that user's `serve`, `run` and `filter` load; bench/README.md, "First live set").
"""

from __future__ import annotations

import argparse
import sys

from kinect_agent.live.warmup import prepare

NAME = "prepare"
HELP = "Compile the filter for this computer once (after an install), so that the first set counts at once."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declares no option: the command has none."""


def run(args: argparse.Namespace) -> int:
    """Fills numba's cache and says how long it took and where the cache is."""
    print(prepare(), file=sys.stderr)
    return 0
