"""`kinect-agent pair --server URL --code CODE [--name NAME]`: exchange a pairing code for a device token, then ready
the filter's compiled code for this computer as `kinect-agent prepare` does (unless --no-prepare), so that the
patient's first set counts as fast as later ones."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from kinect_agent.config import config_path
from kinect_agent.pairing import pair

NAME = "pair"
HELP = "Pair this agent with a patient: exchange the pairing code from the clinic for a device token."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declares the pair options."""
    parser.add_argument("--server", required=True, help="coaching server URL, e.g. https://coach.example.org")
    parser.add_argument("--code", required=True, help="pairing code shown to the patient or therapist, e.g. K7QF-M2XA")
    parser.add_argument("--name", default=None, help="name of this device (default: '<host name> Kinect')")
    parser.add_argument("--queue", type=Path, help="queue folder (default: <agent home>/queue)")
    parser.add_argument("--force", action="store_true", help="pair even though sessions of the old pairing wait")
    parser.add_argument("--no-prepare", action="store_true",
                        help="do not compile the filter now (the agent's first start then does it)")  # fmt: skip


def run(args: argparse.Namespace) -> int:
    """Pairs, prints where the configuration went, and readies the filter (kinect_agent.live.warmup.prepare)."""
    config = pair(args.server, args.code, name=args.name, queue_dir=args.queue, force=args.force)
    print(
        f"paired as device {config.device_id} ({config.device_name}) for patient {config.patient_id} "
        f"on {config.server_url}; configuration in {config_path()}, queue in {config.queue_dir}",
        file=sys.stderr,
    )
    if not args.no_prepare:
        from kinect_agent.live.warmup import prepare  # numba and SciPy: loaded only here

        print("readying the filter for this computer (the first time after an install: about a minute)",
              file=sys.stderr, flush=True)  # fmt: skip
        print(prepare(), file=sys.stderr)
    return 0
