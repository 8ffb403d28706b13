"""`drake-auv`: plan coverage paths, list scenarios, simulate missions, run the demo,
reconstruct surfaces from recorded returns."""

from __future__ import annotations

import argparse
import importlib
import sys

COMMANDS = ("plan", "scenarios", "simulate", "lawnmower", "run", "demo", "reconstruct",
            "campaign")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="drake-auv",
        description="3D coverage planning and simulated inspection for a hovering AUV.")
    subparsers = parser.add_subparsers(dest="command", required=True)
    for name in COMMANDS:
        importlib.import_module(f"drake_auv.commands.{name}").add_parser(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (ValueError, FileNotFoundError) as err:
        print(f"drake-auv {args.command}: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
