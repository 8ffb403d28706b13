"""`drake-auv`: plan coverage paths, list scenarios, simulate missions, run the demo,
reconstruct surfaces from recorded returns."""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings

from drake_auv import __version__

COMMANDS = ("plan", "scenarios", "simulate", "lawnmower", "run", "demo", "reconstruct",
            "campaign", "envelope", "replay")


class OneLineParser(argparse.ArgumentParser):
    """A usage error as every other refusal: one line naming the option, exit 2 (the usage
    itself is in `--help`). Subcommands' parsers are of the same class."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())} (see {self.prog} "
                     "--help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
        prog="drake-auv",
        description="3D coverage planning and simulated inspection for a hovering AUV.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    subparsers = parser.add_subparsers(dest="command", required=True)
    for name in COMMANDS:
        importlib.import_module(f"drake_auv.commands.{name}").add_parser(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Runs one subcommand. Bad input (ValueError) and every OSError end it with one line on
    stderr and exit 2; warnings (e.g. a repaired ROI) are one line each. Run as the program
    (`argv` None: the command line), a batch command (`plan`: its many large temporaries,
    its threads) keeps the memory it frees and hands the GIL over quickly
    (`resources.tune_batch_process`)."""
    args = build_parser().parse_args(argv)
    if argv is None and getattr(args, "batch_process", False):
        from drake_auv.resources import tune_batch_process

        tune_batch_process()
    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warning(args.command)
        try:
            return int(args.func(args) or 0)
        except ValueError as err:
            print(f"drake-auv {args.command}: error: {err}", file=sys.stderr)
        except OSError as err:
            print(f"drake-auv {args.command}: error: {os_error_line(err)}", file=sys.stderr)
    return 2


def os_error_line(err: OSError) -> str:
    """An OSError as one line naming its path(s): 'PATH: No space left on device'; the
    message alone for the project's own FileNotFoundErrors (they name their file)."""
    if err.filename is None:
        return " ".join(str(err).split())
    paths = f"{err.filename}" + (f" -> {err.filename2}" if err.filename2 is not None else "")
    return f"{paths}: {err.strerror or type(err).__name__}"


def _one_line_warning(command: str):
    """A warning as one line of its own, the progress display on its stream cleared around it."""
    def show(message, category, filename, lineno, file=None, line=None):
        from drake_auv.progress import print_line

        text = " ".join(str(message).split())
        print_line(f"drake-auv {command}: warning: {text}", file)
    return show


if __name__ == "__main__":
    sys.exit(main())
