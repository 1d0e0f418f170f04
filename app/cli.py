"""The ``ramure`` command line.

Sub-commands live in :mod:`ramure.app.commands`; each module there registers its own
parsers, so adding a command never touches this file.  Errors a user can fix
(grammar errors, bad values, missing files) are printed as one clear message
without a traceback and exit with status 2.
"""

from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys
from typing import TYPE_CHECKING, TypeAlias

import ramure.app.commands
from ramure.errors import RamureError

if TYPE_CHECKING:
    from argparse import _SubParsersAction

    #: The object every ``register(sub)`` in :mod:`ramure.app.commands` receives.
    Subparsers: TypeAlias = _SubParsersAction[argparse.ArgumentParser]


class UserError(RamureError):
    """An error caused by the user's input: printed without a traceback, exit 2."""


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``ramure`` parser; with a known ``command`` only the module that owns it is imported.

    Without one (``ramure --help``, an unknown or misspelt command) every command module
    registers, so help and argparse's "invalid choice" list are complete."""
    parser = argparse.ArgumentParser(
        prog="ramure",
        description="Explore procedural plants: derive, select, regenerate, measure.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name in _command_modules(command):
        importlib.import_module(f"ramure.app.commands.{name}").register(sub)
    return parser


def _command_modules(command: str | None) -> list[str]:
    owner = ramure.app.commands.OWNERS.get(command or "")
    if owner is not None:
        return [owner]
    return sorted(m.name for m in pkgutil.iter_modules(ramure.app.commands.__path__))


def _command_word(argv: list[str]) -> str | None:
    """The sub-command the user typed: the first word, unless it is an option (``-h``)."""
    return argv[0] if argv and not argv[0].startswith("-") else None


def _user_errors() -> tuple[type[Exception], ...]:
    # Every OSError (missing file, directory instead of file, no permission, full disk,
    # a writer that cannot write) is about the user's paths, not a bug.
    return (RamureError, OSError)


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(_command_word(argv))
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except BrokenPipeError:  # e.g. `ramure leaves ... | head`: before OSError, a quiet exit
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except _user_errors() as exc:
        print(f"ramure {args.command}: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("ramure: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    # Run the imported module's main, so commands and this file share one UserError class.
    from ramure.app.cli import main as _main

    sys.exit(_main())
