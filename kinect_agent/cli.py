"""`kinect-agent`: the home agent's command line. Each subcommand lives in kinect_agent/commands/."""

from __future__ import annotations

import argparse
import importlib
import sys

from kinect_agent import __version__
from kinect_agent.blas_threads import one_blas_thread
from kinect_agent.errors import AgentError

# Subcommand modules; each defines NAME, HELP, add_arguments(parser) and run(args) -> int.
COMMANDS = (
    "kinect_agent.commands.convert",
    "kinect_agent.commands.simulate",
    "kinect_agent.commands.filter",
    "kinect_agent.commands.capture",
    "kinect_agent.commands.pair",
    "kinect_agent.commands.upload",
    "kinect_agent.commands.status",
    "kinect_agent.commands.run",
    "kinect_agent.commands.serve",
    "kinect_agent.commands.evaluate",
    "kinect_agent.commands.export",
)


def build_parser() -> argparse.ArgumentParser:
    """Returns the parser with every available subcommand."""
    parser = argparse.ArgumentParser(prog="kinect-agent", description="Kinect Home Coach home agent.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module_name in COMMANDS:
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name == module_name:
                continue
            raise
        p = sub.add_parser(module.NAME, help=module.HELP, description=module.HELP)
        module.add_arguments(p)
        p.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Runs one subcommand; user errors print one clear line and exit with status 2."""
    args = build_parser().parse_args(argv)
    one_blas_thread()
    try:
        return int(args._run(args) or 0)
    except (AgentError, ValueError) as exc:
        print(f"kinect-agent {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
