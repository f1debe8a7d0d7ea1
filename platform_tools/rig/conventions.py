"""Conventions every command follows.

Exit codes: 0 ok, 1 a check failed, 2 bad input or usage (argparse uses 2 for usage too).
Errors the user can fix are one line on stderr, never a traceback: raise :class:`UserError`
(or let an :class:`InputProblems` such as RigError, or an :class:`OutputError`, through) and :func:`run` prints it.
``-v`` / ``-q`` set logging; ``--json`` prints one JSON document on stdout for scripts.
"""
from __future__ import annotations

import argparse
import json
import logging
import sys
from typing import Any, Callable, Sequence

from platform_tools.rig import progress
from platform_tools.rig.atomic import OutputError
from platform_tools.rig.problems import InputProblems
from platform_tools.rig import DEFAULT_RIG, Rig, load_rig

EXIT_OK = 0
EXIT_CHECK_FAILED = 1
EXIT_BAD_INPUT = 2
#: a command stopped by Ctrl-C or SIGTERM: 128 + SIGINT, as a shell reports a Ctrl-C
EXIT_INTERRUPTED = 130

log = logging.getLogger("platform_tools")


class UserError(Exception):
    """Bad input the user can fix: printed as one line, exit 2."""
    exit_code = EXIT_BAD_INPUT


class CheckFailed(Exception):
    """A check ran and failed: printed as one line, exit 1."""
    exit_code = EXIT_CHECK_FAILED


def add_output_options(parser: argparse.ArgumentParser, *, json_output: bool = True) -> None:
    g = parser.add_argument_group("output")
    if json_output:
        g.add_argument("--json", action="store_true", help="print one JSON document on stdout (for scripts)")
    g.add_argument("-v", "--verbose", action="count", default=0, help="more log messages (-vv for debug)")
    g.add_argument("-q", "--quiet", action="store_true", help="only errors; no progress bars")


def add_rig_options(parser: argparse.ArgumentParser) -> None:
    g = parser.add_argument_group("rig description")
    g.add_argument("--rig", metavar="FILE", default=None,
                   help=f"rig description to use (default: {DEFAULT_RIG.relative_to(DEFAULT_RIG.parents[1])})")
    g.add_argument("--set", metavar="KEY=VALUE", action="append", default=[], dest="overrides",
                   help="override a rig value, e.g. --set sensors.thermal.baseline_mm=150 (repeatable)")


def rig_from_args(args: argparse.Namespace) -> Rig:
    return load_rig(args.rig, args.overrides)


def setup_logging(args: argparse.Namespace) -> None:
    quiet = getattr(args, "quiet", False)
    verbose = getattr(args, "verbose", 0)
    level = logging.ERROR if quiet else (logging.DEBUG if verbose > 1 else
                                         logging.INFO if verbose == 1 else logging.WARNING)
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)
    progress.set_quiet(quiet)


def print_json(obj: Any) -> None:
    json.dump(obj, sys.stdout, indent=2, sort_keys=False, default=str)
    sys.stdout.write("\n")


_prog = "platform_tools"  # the running tool's name, set by dispatch (argv[0] is a path under python -m)


def error(message: str) -> None:
    for line in message.splitlines() or [message]:
        print(f"{_prog}: error: {line}", file=sys.stderr)


def run(handler: Callable[[argparse.Namespace], int | None], args: argparse.Namespace) -> int:
    """Run a command handler with the project's error conventions; returns the exit code."""
    setup_logging(args)
    try:
        code = handler(args)
        return EXIT_OK if code is None else int(code)
    except InputProblems as exc:   # a rig file, a catalogue, steps.yaml ...: one line per problem
        for line in exc.lines:
            error(line)
        return EXIT_BAD_INPUT
    except (UserError, CheckFailed) as exc:
        error(str(exc))
        return exc.exit_code
    except OutputError as exc:
        error(str(exc))
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        error("interrupted")
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        return EXIT_OK


def tool_parser(prog: str, description: str, modules) -> argparse.ArgumentParser:
    """The parser of a console script whose subcommands are ``modules`` (each has ``register(sub)``)."""
    parser = argparse.ArgumentParser(prog=prog, description=description,
                                     epilog="Exit codes: 0 ok, 1 a check failed, 2 bad input or usage.")
    sub = parser.add_subparsers(title="commands", metavar="COMMAND")
    for module in modules:
        module.register(sub)
    return parser


def dispatch(parser: argparse.ArgumentParser, argv: Sequence[str] | None) -> int:
    global _prog
    _prog = parser.prog
    args = parser.parse_args(argv)
    handler = getattr(args, "handler", None)
    if handler is None:
        parser.print_help(sys.stderr)
        return EXIT_BAD_INPUT
    return run(handler, args)
