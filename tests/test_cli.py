"""The command line's shared vocabulary: `--version` and `-o/--out` on every command."""

import pytest

import drake_auv
from drake_auv.cli import COMMANDS, build_parser


def test_version_prints_the_package_version(capsys):
    with pytest.raises(SystemExit) as stop:
        build_parser().parse_args(["--version"])
    assert stop.value.code == 0
    assert capsys.readouterr().out.strip() == f"drake-auv {drake_auv.__version__}"


@pytest.mark.parametrize("command", [c for c in COMMANDS if c != "scenarios"])
def test_every_command_writing_files_takes_o_and_out(command):
    subparser = build_parser()._subparsers._group_actions[0].choices[command]
    flags = {flag for action in subparser._actions for flag in action.option_strings
             if action.dest == "out"}
    assert {"-o", "--out"} <= flags, (command, flags)
