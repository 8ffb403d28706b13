"""The ocean's clock: UTC instants as seconds since 1970-01-01T00:00:00Z (pure Python).

The dive's time t = 0 sits at `start_utc` on this clock; tides, tidal series and gridded
files are all read on it. Calendars other than the proleptic Gregorian one (the CF
`standard`, `gregorian`, `proleptic_gregorian`) are not supported.
"""

from __future__ import annotations

import re
from datetime import datetime, timezone

UTC_FORMAT = "YYYY-MM-DDTHH:MM:SSZ"
TIDE_EPOCH_UTC = "2000-01-01T00:00:00Z"  # the tides' phase reference when no start is given
_UTC = re.compile(r"\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}(\.\d+)?Z")


def parse_utc(text: str, where: str = "start_utc") -> float:
    """Seconds since 1970-01-01T00:00:00Z of `text` ("YYYY-MM-DDTHH:MM:SSZ"); a ValueError
    naming `where` otherwise."""
    if not isinstance(text, str) or not _UTC.fullmatch(text.strip()):
        raise ValueError(f"{where} = {text!r} is not a UTC time; must be {UTC_FORMAT}")
    try:
        moment = datetime.fromisoformat(text.strip()[:-1]).replace(tzinfo=timezone.utc)
    except ValueError as err:
        raise ValueError(f"{where} = {text!r} is not a valid date ({err}); must be "
                         f"{UTC_FORMAT}") from None
    return moment.timestamp()


def format_utc(seconds: float) -> str:
    """`seconds` since the epoch as "YYYY-MM-DDTHH:MM:SSZ" (whole seconds)."""
    return datetime.fromtimestamp(round(seconds), tz=timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")


def parse_reference(text: str, where: str) -> float:
    """Seconds since the epoch of a CF reference time ("1970-01-01", "2024-03-01 12:00:00",
    "2024-03-01T12:00:00Z", "... UTC", "... +00:00"): naive times are UTC."""
    raw = text.strip()
    clean = re.sub(r"\s*(UTC|GMT|Z)$", "", raw, flags=re.IGNORECASE).strip()
    clean = re.sub(r"^(\d{4}-\d{1,2}-\d{1,2})[ T]", r"\1T", clean)
    clean = re.sub(r"\s+([+-]\d{1,2}(:?\d{2})?)$", r"\1", clean)  # " +0:00" offset
    date, _, rest = clean.partition("T")
    parts = date.split("-")
    if len(parts) == 3 and all(p.isdigit() for p in parts):
        date = f"{int(parts[0]):04d}-{int(parts[1]):02d}-{int(parts[2]):02d}"
    try:
        moment = datetime.fromisoformat(f"{date}T{rest}" if rest else date)
    except ValueError:
        raise ValueError(f"{where}: reference time {text!r} is not a date; must be like "
                         "'2024-03-01 00:00:00' (UTC)") from None
    if moment.tzinfo is None:
        moment = moment.replace(tzinfo=timezone.utc)
    return moment.timestamp()
