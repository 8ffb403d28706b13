"""One validator for every parameter dataclass: ranges as field metadata (pure Python).

A parameter is declared once, where its algorithm is, with `param(default, low=..., high=...,
unit=...)` (or `choices=...`, `kind="bool"`, ...); the dataclass calls `validate(self)` from
`__post_init__`, so construction and `dataclasses.replace` both check every field. A bad value
raises `ParameterError`, one line:
`ReplanningParameters.clearance = -1 is out of range; must be in [0.5, 20] m`.

The mission files read the same classes (`drake_auv.mission.spec`): a field's `key` is its name
in a mission file when that differs (`R` for the replanner's `radius`) and `scale` converts the
file's unit to the field's (`math.pi / 180`: degrees in the file, radians in the code);
`nested(cls)` marks a field holding another parameter class whose keyed fields the mission file
sets in the same section.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import MISSING, dataclass
from pathlib import Path

import numpy as np

CHECK = "drake_auv.check"  # field metadata holding the field's `Check`
NESTED = "drake_auv.nested"  # field metadata holding the parameter class of a nested field
KINDS = ("number", "choice", "bool", "text", "path", "vector")


class ParameterError(ValueError):
    """A bad parameter: `Class.field = value is out of range; must be in [low, high] unit`."""

    def __init__(self, owner: str, name: str, value, what: str, allowed: str):
        self.owner, self.name, self.value, self.what, self.allowed = (owner, name, value, what,
                                                                      allowed)
        where = "in " if allowed[:1] in "[(" else ""
        super().__init__(f"{owner}.{name} = {value!r} {what}; must be {where}{allowed}")


@dataclass(frozen=True)
class Check:
    """What a field accepts. kind "number": in [low, high] (ends open when named), `integer`,
    elementwise for an array; "choice": one of `choices`; "bool"; "text": a non-empty string;
    "path": a `pathlib.Path`; "vector": `len(names)` finite numbers (or one of `choices`, a
    word standing for a vector the user of the field works out). `nullable`: None too.
    `unit` is the field's unit, `key` its mission-file name, `scale` file value -> field value,
    `note` replaces the generated description of what is allowed."""

    kind: str = "number"
    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    integer: bool = False
    nullable: bool = False
    choices: tuple = ()
    names: tuple = ()
    unit: str = ""
    key: str | None = None
    scale: float = 1.0
    file_unit: str | None = None
    note: str = ""

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"Check.kind must be one of {', '.join(KINDS)}, got {self.kind!r}")

    def allowed(self, in_file: bool = False) -> str:
        """What is allowed, in the field's unit (`in_file`: the mission file's)."""
        scale, unit = (self.scale, self.file_unit or self.unit) if in_file else (1.0, self.unit)
        if self.note:
            text = self.note
        elif self.kind == "number":
            low, high = self.low / scale, self.high / scale
            if math.isinf(high) and math.isinf(low):
                text = "a number"
            elif math.isinf(high):
                text = f"{'>' if self.low_open else '>='} {low:g}"
            else:
                text = (f"{'(' if self.low_open else '['}{low:g}, {high:g}"
                        f"{')' if self.high_open else ']'}")
            if self.integer:
                text = f"an integer {text}" if math.isinf(high) else f"an integer in {text}"
            text += f" {unit}" if unit else ""
        elif self.kind == "choice":
            text = ", ".join(str(c) for c in self.choices)
        elif self.kind == "bool":
            text = "true or false"
        elif self.kind == "text":
            text = "a string"
        elif self.kind == "path":
            text = "a file path"
        else:
            text = f"[{', '.join(self.names)}] ({unit})" + "".join(
                f" or {c!r}" for c in self.choices)
        return text + (" or null" if self.nullable and self.kind != "bool" else "")

    def problem(self, value) -> str | None:
        """What is wrong with `value` ("is out of range", ...), or None when it is allowed."""
        if value is None:
            return None if self.nullable else "is missing"
        if self.kind == "choice":
            return None if value in self.choices else "is not allowed"
        if self.kind == "bool":
            return None if isinstance(value, (bool, np.bool_)) else "is not a boolean"
        if self.kind == "text":
            ok = isinstance(value, str) and bool(value.strip())
            return None if ok else "is not a non-empty string"
        if self.kind == "path":
            return None if isinstance(value, Path) else "is not a file path"
        if self.kind == "vector":
            ok = (isinstance(value, str) and value in self.choices) or (
                isinstance(value, (list, tuple)) and len(value) == len(self.names)
                and all(is_number(v) and math.isfinite(v) for v in value))
            return None if ok else f"is not {len(self.names)} finite numbers" + "".join(
                f" or {c!r}" for c in self.choices)
        values = np.asarray(value, dtype=object).reshape(-1)
        if not values.size or not all(is_number(v) for v in values):
            return "is not a number"
        values = values.astype(float)
        if self.integer and not np.all(np.isfinite(values) & (np.round(values) == values)):
            return "is not an integer"
        above = values > self.low if self.low_open else values >= self.low
        below = values < self.high if self.high_open else values <= self.high
        return None if np.all(np.isfinite(values) & above & below) else "is out of range"


def is_number(value) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(
        value, (bool, np.bool_))


def param(default=MISSING, *, default_factory=MISSING, kind: str = "number", **check):
    """A dataclass field with its `Check` (keywords: see `Check`) as metadata."""
    return dataclasses.field(default=default, default_factory=default_factory,
                             metadata={CHECK: Check(kind=kind, **check)})


def like(cls, name: str, required: bool = False):
    """A field with the check and default (none when `required`) of `cls.name`: a mission
    step that exposes one of an algorithm's parameters takes both from there."""
    source = next(f for f in dataclasses.fields(cls) if f.name == name)
    return dataclasses.field(default=MISSING if required else source.default,
                             metadata={CHECK: source.metadata[CHECK]})


def nested(cls, default_factory=None):
    """A field holding a `cls` parameter object (default: `default_factory()` or `cls()`)."""
    return dataclasses.field(default_factory=default_factory or cls, metadata={NESTED: cls})


def checks(cls) -> dict:
    """{field name: Check} of the checked fields of dataclass `cls`."""
    return {f.name: f.metadata[CHECK] for f in dataclasses.fields(cls) if CHECK in f.metadata}


def validate(obj) -> None:
    """Checks every field of `obj` that carries a `Check`; raises `ParameterError`."""
    for f in dataclasses.fields(obj):
        check = f.metadata.get(CHECK)
        if check is None:
            continue
        value = getattr(obj, f.name)
        what = check.problem(value)
        if what is not None:
            raise ParameterError(type(obj).__name__, f.name, value, what, check.allowed())


def defaults(cls) -> dict:
    """{field name: default} of the fields of `cls` that have one."""
    out = {}
    for f in dataclasses.fields(cls):
        if f.default_factory is not MISSING:
            out[f.name] = f.default_factory()
        elif f.default is not MISSING:
            out[f.name] = f.default
    return out
