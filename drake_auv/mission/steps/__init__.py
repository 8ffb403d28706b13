"""Mission steps: one module per step kind, and the registry that lists them.

A step kind (`MissionStep`, `drake_auv.mission.steps.step`) is its spec (what the mission
file holds), its file rules, its legs and its behaviour's wiring into the Diagram, all in its
module; `drake_auv.mission.config` reads the steps the registry names, `plan_mission` and
`build_mission_diagram` loop over it. A new built-in kind is a module here and its name in
`BUILT_IN`; a kind of your own is a `MissionStep` subclass passed to `register` (see
`examples/custom_step.py`).
"""

from __future__ import annotations

from importlib import import_module

from drake_auv.mission.steps.step import MissionStep

BUILT_IN = ("plan", "follow", "survey", "fly", "explore", "hover")  # modules of this package

STEPS: dict[str, type[MissionStep]] = {}  # step kind (its file key) -> MissionStep


def register(step: type[MissionStep]) -> type[MissionStep]:
    """Adds the step kind `step` to the registry (its key: `step.spec.KIND`); returns it.
    Raises ValueError for a key or a behaviour name already taken by another kind."""
    kind = step.spec.KIND
    if STEPS.get(kind, step) is not step:
        raise ValueError(f"step kind {kind!r} is already registered ({STEPS[kind].__name__})")
    taken = {s.behaviour: s for s in STEPS.values() if s is not step and s.behaviour}
    if step.behaviour in taken or step.behaviour in ("path", "response"):
        raise ValueError(f"behaviour {step.behaviour!r} of step {kind!r} is already taken")
    STEPS[kind] = step
    return step


def step_specs() -> dict[str, type]:
    """{step kind: its spec class}, in the registry's order."""
    return {kind: step.spec for kind, step in STEPS.items()}


def behaviour_step(name: str) -> type[MissionStep]:
    """The step kind whose behaviour is called `name`; ValueError when none is."""
    for step in STEPS.values():
        if step.behaviour == name:
            return step
    raise ValueError(f"no registered step kind flies the behaviour {name!r} (behaviours: "
                     f"{', '.join(s.behaviour for s in STEPS.values() if s.behaviour)})")


for _module in BUILT_IN:
    register(import_module(f"{__name__}.{_module}").STEP)
