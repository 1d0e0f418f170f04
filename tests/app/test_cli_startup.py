"""``ramure COMMAND`` imports only the module that owns COMMAND.

Every command module registered at start-up used to cost each call about 1 s of imports
(the 3G-map kernel, numba's compiled kernels, manifold3d) before any work."""

from __future__ import annotations

import argparse
import importlib
import json
import pkgutil
import subprocess
import sys

import pytest

import ramure.app.commands
from ramure.app.cli import build_parser, main

HEAVY = ("numba", "scipy", "pyvista", "vtkmodules", "manifold3d", "sklearn", "matplotlib", "ramure.gmap")


def _registered(module_name: str) -> list[str]:
    sub = argparse.ArgumentParser().add_subparsers(dest="command")
    importlib.import_module(f"ramure.app.commands.{module_name}").register(sub)
    return list(sub.choices)


def test_the_owner_table_names_every_command_of_every_module():
    modules = sorted(m.name for m in pkgutil.iter_modules(ramure.app.commands.__path__))
    found = {command: name for name in modules for command in _registered(name)}
    assert found == ramure.app.commands.OWNERS


@pytest.mark.parametrize("command", sorted(ramure.app.commands.OWNERS))
def test_a_known_command_registers_its_own_module_only(command):
    choices = build_parser(command)._subparsers._group_actions[0].choices  # type: ignore[union-attr]
    owner = ramure.app.commands.OWNERS[command]
    assert sorted(choices) == sorted(_registered(owner))


def test_help_and_an_unknown_command_list_every_command(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["chek", "x"])
    assert stop.value.code == 2
    listed = capsys.readouterr().err
    for command in ramure.app.commands.OWNERS:
        assert f"'{command}'" in listed


def _loaded_after(code: str) -> list[str]:
    probe = f"import sys, json\n{code}\nprint(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))"
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    return json.loads(done.stdout.splitlines()[-1])


def test_checking_a_grammar_loads_no_kernel_and_no_plotting():
    code = "from ramure.app.cli import main\nassert main(['check', 'honda_sympodial']) == 0"
    assert _loaded_after(code) == []


def test_the_fruit_command_still_gets_its_libraries():
    # The owner's own imports still happen: the table skips other commands, not this one's.
    assert "ramure.gmap" in _loaded_after("from ramure.app.cli import build_parser\nbuild_parser('fruit')")
