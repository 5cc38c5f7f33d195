"""The ``iwanfe`` command: parses, calls, prints.

Every sub-command lives in ``cli/commands/<name>.py``. The rules every command follows:

Bad input
    Every argument and input file is checked before any work starts. Bad input
    (:class:`ident.errors.InputError`, a ``ValueError`` raised by the project's own
    checks, or an unreadable file) ends with one line on stderr naming the input and the
    reason, and exit status 2; never a traceback. A failure that is not the input's
    fault (a solver that does not converge, a ``ValueError`` or ``LinAlgError`` raised
    inside numpy or scipy: :func:`input_fault`) is one line too, with exit status 1
    (``IWANFE_TRACEBACK=1`` shows where).
Interrupts
    Ctrl-C prints ``iwanfe: interrupted`` and exits with status 130, without traceback,
    wherever it lands (compiled code included: :mod:`runs.interrupt` defers it to the
    next safe point while compiled code runs); finished work already stored stays
    stored, and a rerun resumes from it.
Output paths
    An output *file* (``--out FILE``, ``--plot FILE``) goes into an existing folder: no
    folder is created for a file. An output *folder* (``--out DIR``) is created with its
    missing parents, unless the first folder to create would sit directly in the
    filesystem root (``/nonexistent/out`` is a typo, refused). Either way the path is
    checked before the work starts (:mod:`cli.validate`).
Output format
    A readable table by default, one JSON document on stdout with ``--json``.
"""
from __future__ import annotations

import argparse
import importlib
import os
import re
import sys
from pathlib import Path

# One BLAS thread unless the user says otherwise, set before numpy loads: the models
# are small (hundreds of DOFs), threads only contend on a few cores, and a serial run
# then gives bitwise the numbers of worker processes (which run one thread each).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

from runs import interrupt  # noqa: E402  (numpy-free: installs the Ctrl-C handler)

# Sub-command modules in the order --help lists them.
COMMANDS = [
    "joint",
    "case",
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
    "loop",
    "ringdown",
    "frc",
]

#: A command-line word that is a number, not an option: argparse's own pattern misses
#: exponents and the IEEE words (``--amplitude -1e-3`` read as an unknown option).
_NUMBER = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$|^-(inf|infinity|nan)$", re.I)


class _HelpFormatter(argparse.HelpFormatter):
    """Adds ``(default: X)`` to an option's help once: not when the help already says
    its default, not for a None default, and not for on/off flags."""

    def _get_help_string(self, action):
        text = action.help or ""
        if (action.default is None or action.default is argparse.SUPPRESS
                or text is argparse.SUPPRESS or "default" in text.lower()
                or isinstance(action, (argparse._StoreTrueAction, argparse._StoreFalseAction,
                                       argparse._StoreConstAction))
                or action.option_strings == []):
            return text
        return text + " (default: %(default)s)"


class _Parser(argparse.ArgumentParser):
    """ArgumentParser whose usage errors are one line and exit status 2, which reads
    ``-1e-3`` as a number, and whose help prints each default once."""

    def __init__(self, *args, **kwargs):
        kwargs["formatter_class"] = _HelpFormatter
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NUMBER

    def error(self, message: str) -> None:  # noqa: D401 - argparse API
        self.exit(2, f"{self.prog}: error: {message}".splitlines()[0] + "\n")


def build_parser(argv=None) -> argparse.ArgumentParser:
    """The ``iwanfe`` parser. When ``argv`` starts with a command's name only that
    command's module is imported (a command starts without importing every other one's
    dependencies); otherwise (``--help``, a typo) every command is registered."""
    first = next((a for a in (argv or []) if not a.startswith("-")), None)
    names = [first] if first in COMMANDS else COMMANDS
    parser = _Parser(
        prog="iwanfe",
        description=(
            "Nonlinear dynamics of structures with slipping joints: four-parameter Iwan "
            "joints, beam FE models, stepped-sine simulation, identification of chi and R "
            "from damping growth, prediction at untested levels, and model diagnosis."
        ),
    )
    parser.add_argument("--units-confirmed", action="store_true",
                        help="values that look like another unit (a case file in "
                             "millimetres, E in MPa, zeta in percent) are right: run on "
                             "instead of stopping with one line (ident.units)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    for name in names:
        try:
            module = importlib.import_module(f"cli.commands.{name}")
        except ModuleNotFoundError as exc:  # command not built yet
            if exc.name == f"cli.commands.{name}":
                continue
            raise
        module.register(sub)
    return parser


def _interrupted() -> int:
    print("iwanfe: interrupted", file=sys.stderr)
    return 130


def _one_line(prefix: str, exc: BaseException) -> str:
    msg = str(exc) or exc.__class__.__name__
    lines = [s for s in f"{prefix}{msg}".splitlines() if s.strip()]
    return lines[0] if lines else prefix + exc.__class__.__name__


#: Top-level packages whose own ``ValueError`` is a verdict on the input.
PROJECT_PACKAGES = ("joints", "fe", "runs", "ident", "inverse", "viz", "synthetic", "casefile",
                    "feloop", "cases", "cli")
_ROOT = Path(__file__).resolve().parents[1]


def input_fault(exc: BaseException) -> bool:
    """Whether ``exc`` says the input is bad (exit 2) rather than the program failed
    (exit 1): an ``InputError`` or an ``OSError`` always; a ``ValueError`` only when the
    project raised it itself (its innermost frame lies in a project package): one raised
    inside numpy or scipy (a singular matrix, an optimizer's inconsistent bounds) is an
    internal failure, whatever its class."""
    from ident.errors import InputError

    if isinstance(exc, (InputError, OSError)):
        return True
    if not isinstance(exc, ValueError) or type(exc).__name__ == "LinAlgError":
        return False
    tb = exc.__traceback__
    if tb is None:
        return True
    while tb.tb_next is not None:
        tb = tb.tb_next
    try:
        rel = Path(tb.tb_frame.f_code.co_filename).resolve().relative_to(_ROOT)
    except ValueError:
        return False
    return rel.parts[0] in PROJECT_PACKAGES


def _run(argv) -> int:
    """Parse ``argv`` and run the chosen command."""
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 0
    if not args.units_confirmed:
        return int(args.func(args) or 0)
    from ident.units import ENVIRONMENT      # numpy-free; worker processes inherit it

    before = os.environ.get(ENVIRONMENT)
    os.environ[ENVIRONMENT] = "1"
    try:
        return int(args.func(args) or 0)
    finally:
        if before is None:
            os.environ.pop(ENVIRONMENT, None)
        else:
            os.environ[ENVIRONMENT] = before


def main(argv: list[str] | None = None) -> int:
    """Run one command; returns the exit status (0, 1, 2 or 130, see module docstring).

    Called without ``argv`` (the installed ``iwanfe`` script), Ctrl-C stays recorded but
    harmless after the command returned, while the interpreter exits; called with
    ``argv`` (tests, scripts) the previous SIGINT handler is restored."""
    return run_guarded(lambda: _run(argv), restore=argv is not None)


def run_guarded(call, restore: bool = True) -> int:
    """``call()`` under the command line's rules for errors and Ctrl-C (module
    docstring); its return value (an int or None) is the exit status."""
    interrupt.install()
    try:
        try:
            code = int(call() or 0)
        except SystemExit as exc:  # argparse: --help (0) or a usage error (2)
            if interrupt.requested() and exc.code not in (0, None):
                return _interrupted()
            raise
        except KeyboardInterrupt:
            return _interrupted()
        except Exception as exc:
            if interrupt.requested() or interrupt.caused_by_interrupt(exc):
                return _interrupted()
            if input_fault(exc):
                print(_one_line("iwanfe: error: ", exc), file=sys.stderr)
                return 2
            # not the input's fault: one line, exit 1
            if os.environ.get("IWANFE_TRACEBACK"):
                raise
            print(_one_line(f"iwanfe: failed: {exc.__class__.__name__}: ", exc)
                  + " (IWANFE_TRACEBACK=1 shows where)", file=sys.stderr)
            return 1
        if interrupt.requested():  # a Ctrl-C that some library swallowed
            return _interrupted()
        return code
    finally:
        if restore:
            interrupt.uninstall()
        else:
            interrupt.quiet()


if __name__ == "__main__":
    sys.exit(main())
