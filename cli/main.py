"""The ``iwanfe`` command: parses, calls, prints.

Every sub-command lives in ``cli/commands/<name>.py``. Bad input (``ValueError``,
including :class:`ident.errors.InputError`, or an unreadable file) is reported as one
line on stderr with exit status 2, never as a traceback.
"""
from __future__ import annotations

import argparse
import importlib
import os
import sys

# One BLAS thread unless the user says otherwise, set before numpy loads: the models
# are small (hundreds of DOFs), threads only contend on a few cores, and a serial run
# then gives bitwise the numbers of worker processes (which run one thread each).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

# Sub-command modules in the order --help lists them.
COMMANDS = [
    "joint",
    "modes",
    "convergence",
    "render",
    "export",
    "identify",
    "estimate",
    "reproduce",
    "uncertainty",
    "diagnose",
    "backbone",
    "update",
]


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose usage errors are one line and exit status 2."""

    def error(self, message: str) -> None:  # noqa: D401 - argparse API
        self.exit(2, f"{self.prog}: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="iwanfe",
        description=(
            "Nonlinear dynamics of structures with slipping joints: four-parameter Iwan "
            "joints, beam FE models, stepped-sine simulation, identification of chi and R "
            "from damping growth, prediction at untested levels, and model diagnosis."
        ),
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name in COMMANDS:
        try:
            module = importlib.import_module(f"cli.commands.{name}")
        except ModuleNotFoundError as exc:  # command not built yet
            if exc.name == f"cli.commands.{name}":
                continue
            raise
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    try:
        return int(args.func(args) or 0)
    except (ValueError, OSError) as exc:
        msg = str(exc) or exc.__class__.__name__
        print(f"iwanfe: error: {msg}".splitlines()[0], file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("iwanfe: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
