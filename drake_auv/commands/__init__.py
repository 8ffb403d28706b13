"""Subcommands of the `drake-auv` console script: each module has `add_parser(subparsers)`
that registers its arguments and sets `func` to the function that runs it."""
