"""`kinect-agent`: the home agent's command line. Each subcommand lives in kinect_agent/commands/<name>.py.

A command imports only its own module (`kinect-agent status` does not load the filter, numba and SciPy that
`run` needs); the full list is built for `--help`, `--version` and a name that is not a command.
"""

from __future__ import annotations

import argparse
import gc
import importlib
import sys
from collections.abc import Iterator
from contextlib import contextmanager

from kinect_agent import __version__
from kinect_agent.blas_threads import one_blas_thread
from kinect_agent.disk_full import is_disk_full, plain_words
from kinect_agent.errors import AgentError
from kinect_agent.processing.errors import ProcessingError

# Subcommand modules, named as their command; each defines NAME, HELP, add_arguments(parser) and run(args) -> int.
COMMANDS = (
    "kinect_agent.commands.convert",
    "kinect_agent.commands.simulate",
    "kinect_agent.commands.filter",
    "kinect_agent.commands.capture",
    "kinect_agent.commands.pair",
    "kinect_agent.commands.prepare",
    "kinect_agent.commands.upload",
    "kinect_agent.commands.status",
    "kinect_agent.commands.run",
    "kinect_agent.commands.serve",
    "kinect_agent.commands.evaluate",
    "kinect_agent.commands.export",
)


@contextmanager
def cycle_collector_paused() -> Iterator[None]:
    """Pauses Python's cyclic garbage collector for the block (and restores it as it was). Loading a command's
    modules and filtering a 10-minute recording leave ≈ 1 400 objects in reference cycles, but allocate millions of
    objects (modules, the CSV's rows and cells, numba's kernels loaded from its cache) that the collector walked
    340 times, ≈ 0.2 s CPU of `kinect-agent filter` (bench/README.md, "Speed on hard recordings"); the cycles are
    collected after the block."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """Returns the parser with every available subcommand, or with the subcommand `only` alone."""
    parser = argparse.ArgumentParser(prog="kinect-agent", description="Kinect Home Coach home agent.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module_name in COMMANDS:
        if only is not None and module_name.rpartition(".")[2] != only:
            continue
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
    """Runs one subcommand. Bad input prints one clear line and exits with status 2; an internal fault of the
    processing (ProcessingError) says so and exits with status 1, as does a full disk (in plain words).

    Run as the program (argv None: the `kinect-agent` script), it freezes the objects left at the end (gc.freeze):
    the process exits next, and the interpreter's final garbage collections would walk every object that numba,
    SciPy and numpy loaded, 0.3 s CPU after `kinect-agent filter` (bench/README.md, "Speed on hard recordings").
    The commands close their files and connections themselves (`with` blocks), not through the collector.
    """
    program = argv is None
    try:
        return _main(argv if argv is not None else sys.argv[1:])
    finally:
        if program:
            gc.freeze()


def _main(argv: list[str]) -> int:
    first = next((a for a in argv if not a.startswith("-")), None)  # the command: no top-level option takes a value
    known = {m.rpartition(".")[2] for m in COMMANDS}
    with cycle_collector_paused():  # importing the command's modules
        args = build_parser(first if first in known else None).parse_args(argv)
    one_blas_thread()
    try:
        return int(args._run(args) or 0)
    except (AgentError, ValueError) as exc:
        print(f"kinect-agent {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except ProcessingError as exc:
        print(f"kinect-agent {args.command}: internal fault ({type(exc).__name__}): {exc}. The input was accepted; "
              "this is a fault of the program, please report it with the input file.", file=sys.stderr)  # fmt: skip
        return 1
    except OSError as exc:
        if not is_disk_full(exc):
            raise
        print(f"kinect-agent {args.command}: {plain_words(exc)} Then run the command again.", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
