"""One module per ``ramure`` sub-command group.

Each module defines ``register(subparsers)`` which adds its parsers and sets
``func`` (a callable ``args -> int`` exit code) on each of them.

:data:`OWNERS` names the module that registers each sub-command, so ``ramure check``
imports only :mod:`.plant` instead of every command's libraries (the 3G-map kernel,
numba, manifold3d, ...), about 1 s per call.  A command missing from it still works:
every module is then imported, as for ``ramure --help``.  ``tests/app/test_cli_startup.py``
checks the table against what the modules register.
"""

#: sub-command -> module of :mod:`ramure.app.commands` that registers it.
OWNERS: dict[str, str] = {
    "amap": "amap",
    "mtg": "amap",
    "autumn": "autumn",
    "import": "convert",
    "crack": "crack",
    "explore": "explore",
    "metrics": "explore",
    "qualify": "explore",
    "export": "export",
    "fruit": "fruit",
    "lichen": "lichen",
    "check": "plant",
    "derive": "plant",
    "render": "plant",
    "leaves": "regen",
    "regen": "regen",
    "study": "study",
    "wood": "wood",
}
