"""Subcommands of the `drake-auv` console script: each module has `add_parser(subparsers)`
that registers its arguments and sets `func` to the function that runs it."""

import argparse
import dataclasses


def whole_number(text: str) -> int:
    """An integer option's value: digits, or a whole number written with an exponent or a
    point ("1e9", "4.0"), so that a count out of range reaches its range check (which states
    the range) instead of a type error."""
    try:
        return int(text)
    except ValueError:
        pass
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not value.is_integer():
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number")
    return int(value)


def check_plan_options(options) -> None:
    """ValueError naming the option, its value and what is allowed for the first (option,
    value, field) of `options` out of range for `field` of the mission plan step (`PlanStep`,
    whose planner fields are `CoverageParameters`': one source of truth for the command line,
    the mission file and the API) or else of `CoverageParameters`, before any work."""
    from drake_auv.mission.steps.plan import PlanStep
    from drake_auv.params import checks, is_number
    from drake_auv.planning.parameters import CoverageParameters

    allowed = {**checks(CoverageParameters), **checks(PlanStep)}
    for option, value, field in options:
        check = allowed[field]
        what = check.problem(value)
        if what is not None:
            shown = f"{value:g}" if is_number(value) else repr(value)
            raise ValueError(f"{option} {shown} {what}; allowed: {option_range(check)}")


def option_range(check) -> str:
    """What an option checked by `check` allows (an option left out stands for a None)."""
    return dataclasses.replace(check, nullable=False).allowed()


def add_recording_options(parser, playback_speed: float, realtime: bool = True) -> None:
    """The options every simulating command shares: the recording's playback speed,
    `--no-html`, `--quiet` and, with `realtime`, pacing the simulation to watch it live."""
    parser.add_argument("--playback-speed", type=float, default=playback_speed,
                        help="the HTML animation plays this many times faster than real time "
                             f"(default {playback_speed:g})")
    if realtime:
        parser.add_argument("--realtime", "--realtime-rate", dest="realtime_rate", type=float,
                            default=0.0, metavar="R",
                            help="pace the simulation to watch it live at R times real time "
                                 "(default 0 = as fast as possible; --realtime-rate is its "
                                 "older spelling)")
    parser.add_argument("--no-html", action="store_true", help="skip the Meshcat recording")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
