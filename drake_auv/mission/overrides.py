"""The `--set` override language: `dotted.key=value` strings applied to a raw mission mapping
before it is validated (`drake_auv.mission.config.load_mission`), so a campaign or the command
line changes one parameter of a file without editing it. Keys are checked against the schema
(`drake_auv.mission.spec.mission_keys`), not the file, so a section the file leaves out can be
set; values are read as YAML.
"""

from __future__ import annotations

import copy
import re

import yaml

from drake_auv.mission.spec import (FAULT_CLASSES, REALISTIC_NOISE, SECTIONS, TOP_KEYS,
                                    MissionFileError, SensorSpec, mission_keys)
from drake_auv.mission.steps import step_specs
from drake_auv.mission.yaml_text import load_yaml
from drake_auv.ocean.spec import OCEAN_KEYS, PARTS
from drake_auv.ocean.tides import TidalConstituent
from drake_auv.params import checks
from drake_auv.sonar.noise import SonarNoise


def apply_overrides(raw: dict, overrides, label: str = "--set") -> dict:
    """A copy of `raw` with each `dotted.key=value` set (value read as YAML; step index as in
    `steps.2.survey.replanning`). Keys are checked against the schema, not the file, so a
    section the file leaves out can be set."""
    out = copy.deepcopy(raw) if isinstance(raw, dict) else {}
    for item in overrides:
        if not isinstance(item, str) or "=" not in item:
            raise MissionFileError(label, str(item), "not a KEY=VALUE override",
                                   "dotted.key=value, e.g. replanner.optimizer=none")
        key, text = item.split("=", 1)
        key = re.sub(r"\[(\d+)\]", r".\1", key.strip())
        try:
            value = load_yaml(text)
        except yaml.YAMLError as err:
            raise MissionFileError(label, key, f"value {text!r} is not YAML ({one_line(err)})",
                                   "a YAML value: number, string, true/false, null, [..], {..}")
        _set(out, key.split("."), value, label)
    return out


def _set(raw: dict, parts: list[str], value, label: str):
    """Sets raw[parts...] = value, checking each key against what the schema allows there."""

    def fail(i: int, what: str, allowed):
        raise MissionFileError(label, ".".join(parts[:i + 1]), what, ", ".join(allowed))

    head, rest = parts[0], parts[1:]
    if head not in TOP_KEYS:
        fail(0, "unknown key", TOP_KEYS)
    if not rest:
        raw[head] = value
        return
    if head == "steps":
        steps = raw.get("steps")
        count = len(steps) if isinstance(steps, list) else 0
        if not (rest[0].isdigit() and int(rest[0]) < count):
            fail(1, "no such step", [str(i) for i in range(count)] or ["(the file has none)"])
        index = int(rest[0])
        step = steps[index]
        if isinstance(step, str):
            kind = step
        else:
            kind = next(iter(step)) if isinstance(step, dict) and len(step) == 1 else None
        specs = step_specs()
        if kind not in specs:
            fail(1, "not a valid step to set keys in", specs)
        if len(rest) == 1:
            steps[index] = value
            return
        if rest[1] != kind:
            fail(2, f"step {index} is a {kind} step", [kind])
        if len(rest) == 2:
            steps[index] = {kind: value}
            return
        if isinstance(step, str) or step[kind] is None:
            step = steps[index] = {kind: {}}
        node, keys, offset = step[kind], tuple(mission_keys(specs[kind])), 3
    elif head == "sonar_noise":
        preset = raw.get("sonar_noise")
        node = (dict(REALISTIC_NOISE) if preset in (None, "realistic")
                else preset if isinstance(preset, dict) else {})
        raw["sonar_noise"], keys, offset = node, tuple(mission_keys(SonarNoise)), 1
    elif head == "faults":  # faults.<kind>.<key>
        if not isinstance(raw.get(head), dict):
            raw[head] = {}
        if rest[0] not in FAULT_CLASSES:
            fail(1, "unknown fault", FAULT_CLASSES)
        if len(rest) == 1:
            raw[head][rest[0]] = value
            return
        if not isinstance(raw[head].get(rest[0]), dict):
            raw[head][rest[0]] = {}
        node, keys, offset = raw[head][rest[0]], tuple(mission_keys(FAULT_CLASSES[rest[0]])), 2
    elif head == "ocean":  # ocean.<part>.<key>, ocean.tides.<i>.<key>, ocean.<value>
        if not isinstance(raw.get(head), dict):  # still water ("none") becomes a sea
            raw[head] = {}
        sea, part = raw[head], rest[0]
        if part not in OCEAN_KEYS:
            fail(1, "unknown key", OCEAN_KEYS)
        if len(rest) == 1:
            sea[part] = value
            return
        if part == "tides":
            tides = sea.get("tides")
            count = len(tides) if isinstance(tides, list) else 0
            if not (rest[1].isdigit() and int(rest[1]) < count):
                fail(2, "no such constituent",
                     [str(i) for i in range(count)] or ["(the file has none)"])
            index = int(rest[1])
            if len(rest) == 2:
                tides[index] = value
                return
            if not isinstance(tides[index], dict):
                tides[index] = {}
            node, keys, offset = tides[index], tuple(checks(TidalConstituent)), 3
        elif part in PARTS:
            if not isinstance(sea.get(part), dict):
                sea[part] = {}
            node, keys, offset = sea[part], tuple(checks(PARTS[part])), 2
        else:
            fail(1, f"{part} is a value, not a section", [f"ocean.{part}"])
    elif head == "payload" and rest[0] == "sensors":  # payload.sensors.<name>.<key>
        if not isinstance(raw.get(head), dict):
            raw[head] = {}
        if len(rest) == 1:
            raw[head]["sensors"] = value
            return
        if not isinstance(raw[head].get("sensors"), dict):
            raw[head]["sensors"] = {}
        table, name = raw[head]["sensors"], rest[1]
        if len(rest) == 2:
            table[name] = value
            return
        if not isinstance(table.get(name), dict):
            table[name] = {}
        node, keys, offset = table[name], tuple(mission_keys(SensorSpec)), 3
    elif head in SECTIONS:
        if not isinstance(raw.get(head), dict):
            raw[head] = {}
        node, keys, offset = raw[head], tuple(mission_keys(SECTIONS[head])), 1
    else:
        fail(1, f"{head} is a value, not a section", [head])
    leaf = parts[offset:]
    if not leaf:
        fail(offset - 1, "needs a key below it", keys)
    if leaf[0] not in keys:
        fail(offset, "unknown key", keys)
    if len(leaf) > 1:
        fail(offset + 1, f"{leaf[0]} is a value, not a section", [".".join(parts[:offset + 1])])
    node[leaf[0]] = value


def one_line(err: Exception) -> str:
    return " ".join(str(err).split())
