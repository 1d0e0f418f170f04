"""The environment a cpfg model's ``?E`` modules talk to (cpfg's ``-e file.e``), when Ramure has it built in.

cpfg runs an environment program beside the model; the ``.e`` file names it
(``executable: honda81 density.spec``).  Ramure runs no program: it has one environment built
in, **honda81** (vlab's ``ENVIRO/honda81``: Honda's 1981 density rule, used by the open
L-systems of vlab's ``07-Open`` collection), answered by
:func:`ramure.lsys.interpretation.environment.honda81`.  Its specification file sets
``radius:`` (default 0) and ``3d case: on|off`` (default off).

Which ``.e`` file: the one with the ``.l`` file's own name, else the only ``.e`` beside it.
Any other program is refused with its name, where the first ``?E`` stands (the reader says
so), and so is a model with no ``.e`` file.  Files are read only inside the ``.l`` file's
folder.
"""

from __future__ import annotations

import os
import pathlib
import re

from .cpfg_functions import read_confined

#: Environment programs Ramure answers itself.
BUILT_IN = ("honda81",)


def environment_file(l_file: str | os.PathLike) -> pathlib.Path | None:
    """The ``.e`` file of a cpfg ``.l`` file: same name, else the only ``.e`` beside it."""
    path = pathlib.Path(l_file)
    same = path.with_suffix(".e")
    if same.is_file():
        return same
    others = sorted(path.parent.glob("*.e"))
    return others[0] if len(others) == 1 else None


def read_environment(l_file: str | os.PathLike, root: pathlib.Path) -> dict:
    """What the ``.e`` file of ``l_file`` names: ``{"program": name, "file": .e path}`` and, for a
    built-in program, its settings (honda81: ``radius``, ``3d``); ``{}`` without an ``.e`` file."""
    e_file = environment_file(l_file)
    if e_file is None:
        return {}
    text = read_confined(e_file, root, None)
    m = re.search(r"^[ \t]*executable[ \t]*:[ \t]*(\S+)(.*)$", text, re.M)
    if m is None:
        return {"program": "", "file": str(e_file)}
    program = pathlib.PurePath(m.group(1)).name
    out: dict = {"program": program, "file": str(e_file)}
    if program == "honda81":
        words = m.group(2).split()
        spec = words[-1] if words and not words[-1].startswith("-") else None
        out.update(radius=0.0, **{"3d": False})
        if spec is not None:
            line = text[: m.start()].count("\n") + 1
            body = read_confined(e_file.parent / spec, root, (str(e_file), line, m.group(0)))
            radius = re.search(r"^[ \t]*radius[ \t]*:[ \t]*([-+0-9.eE]+)", body, re.M)
            three = re.search(r"^[ \t]*3d case[ \t]*:[ \t]*(\w+)", body, re.M)
            out["radius"] = float(radius.group(1)) if radius else 0.0
            out["3d"] = bool(three and three.group(1) == "on")
    return out
