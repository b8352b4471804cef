"""The ``ipmc`` subcommands, one module each: ``add_parser(subparsers)`` and ``run(args) -> int``.

A new subcommand is one new module here, listed in :data:`scenarios.cli.COMMANDS`.
"""
