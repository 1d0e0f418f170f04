"""One module per ``ramure`` sub-command group.

Each module defines ``register(subparsers)`` which adds its parsers and sets
``func`` (a callable ``args -> int`` exit code) on each of them.
"""
