"""`MissionSupervisor`: flies a mission's legs in order and ends the dive.

Every `period` s it judges the current leg (`drake_auv.mission.legs.goal_reached`: from the
estimated state and the behaviours' status, never the true world) and, when the leg is done
by its goal or its time budget, starts the next one. Its `leg` output tells the behaviours
which leg flies and since when; its `behaviour` output selects the tracker's reference in a
`PortSwitch`. After the last leg `done` is set, and `monitor` (a Simulator monitor) ends the
simulation with `EventStatus.ReachedTermination`.

It also applies the safety rules (`drake_auv.mission.safety`): from the sonars' returns, the
reference being tracked and the estimated state it detects a silent sonar, a tracking error
that grows (a failed thruster) and a jump of the estimate, and answers by holding, backing off
from the mapped structure or aborting to the surface. While a response flies, `behaviour`
selects the switch's `response` input, fed by `response_reference`; an abort ends the dive.

Discrete-state groups, each with its view in `drake_auv.signals`: `leg` (`LegSignal`),
`progress` (of the current leg: `LegProgress`), `outcomes` (per leg: 0 not ended, 1 goal
reached, 2 timed out, 3 aborted), `done` (1 after the last leg or an abort), `watch` (`Watch`),
`heard` (per watched sensor, in `sensors` order: the time of its last update with beams, s)
and `response` (`Response`).

Ports: inputs `estimated_state` (`VehicleState`), one `<behaviour>_status`
(`BehaviourStatus`) per behaviour it sequences (`path_status`, `follow_status`, ...: a leg's
goal reads its own behaviour's), `{name}_returns` (`SonarReturns`) per watched sensor,
`reference` (`Reference`), `map` (`OnlineMap`) (all but the first may be left unconnected: the
rule that needs one is then off); outputs `leg` (`LegSignal`), `behaviour` (`InputPortIndex`), `response` (`Response`,
the group, for a log) and `response_reference` (`Reference`).
"""

from __future__ import annotations

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.framework import EventStatus, InputPortIndex, LeafSystem

from drake_auv.mapping.mapper import OnlineMap
from drake_auv.mission.legs import (Leg, advance_progress, goal_reached, leg_share,
                                    start_progress)
from drake_auv.mission.safety import (CAUSES, DRIFT_WINDOWS, RESPONSES, SafetyRules,
                                      abort_target, back_off_target, closing, drifting,
                                      relied_sensors, response_record, response_reference,
                                      uncommanded)
from drake_auv.signals import (BehaviourStatus, LegProgress, LegSignal, Reference, Response,
                               VehicleState, Watch)
from drake_auv.sonar.returns import SonarReturns

OUTCOMES = ("flying", "goal", "timed out", "aborted")


class MissionSupervisor(LeafSystem):
    """Sequences `legs`.

    Args:
        legs: the mission's legs, in order (at least one).
        behaviour_ports: {behaviour name: index of the PortSwitch input it drives}, and
            "response" for the `response_reference` output (needed by the safety rules); each
            behaviour's status is read from the input `<name>_status` (`status_inputs`).
        period: judging period, s, in (0, 5].
        rules: the `SafetyRules` (default thresholds).
        sensors: the names of the sonars whose returns it watches (`mission.safety.
            relied_sensors`: a leg relying on one that falls silent is held), an input
            `{name}_returns` each (none: no silent-sonar rule).
    """

    def __init__(self, legs: tuple[Leg, ...], behaviour_ports: dict[str, int],
                 period: float = 0.5, rules: SafetyRules | None = None,
                 sensors=()):
        super().__init__()
        if not legs:
            raise ValueError("a mission needs at least one leg")
        missing = {leg.behaviour for leg in legs} - set(behaviour_ports)
        if missing:
            raise ValueError(f"no PortSwitch input for behaviour(s) {sorted(missing)}")
        if not (np.isfinite(period) and 0 < period <= 5.0):
            raise ValueError(f"MissionSupervisor period must be in (0, 5] s, got {period}")
        self.legs = tuple(legs)
        # the legs' time budgets summed before each leg, and all of them
        self._budgets = np.r_[0.0, np.cumsum([leg.max_duration for leg in self.legs])]
        self.period = float(period)
        self.behaviour_ports = dict(behaviour_ports)
        self.rules = rules if rules is not None else SafetyRules()
        self.state_input = self.DeclareVectorInputPort("estimated_state", VehicleState.size())
        self.status_inputs = {name: self.DeclareVectorInputPort(f"{name}_status",
                                                                BehaviourStatus.size())
                              for name in self.behaviour_ports if name != "response"}
        empty = AbstractValue.Make(SonarReturns.empty(1.0))
        self.returns_inputs = {name: self.DeclareAbstractInputPort(f"{name}_returns", empty)
                               for name in sensors}
        self.reference_input = self.DeclareVectorInputPort("reference", Reference.size())
        self.map_input = self.DeclareAbstractInputPort("map", AbstractValue.Make(OnlineMap(0.5)))
        self._leg = self.DeclareDiscreteState(LegSignal.size())
        self._progress = self.DeclareDiscreteState(LegProgress.size())
        self._outcomes = self.DeclareDiscreteState(len(self.legs))
        self._done = self.DeclareDiscreteState(1)
        self._watch = self.DeclareDiscreteState(Watch.size())
        self._heard = self.DeclareDiscreteState(max(len(self.returns_inputs), 1))
        self._response = self.DeclareDiscreteState(Response.size())
        self.DeclareInitializationDiscreteUpdateEvent(self._start_mission)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update_leg)
        self.leg_output = self.DeclareStateOutputPort("leg", self._leg)
        self.behaviour_output = self.DeclareAbstractOutputPort(
            "behaviour", lambda: AbstractValue.Make(InputPortIndex(0)), self._calc_behaviour,
            prerequisites_of_calc={self.discrete_state_ticket(self._leg),
                                   self.discrete_state_ticket(self._response)})
        self.response_output = self.DeclareStateOutputPort("response", self._response)
        self.response_reference_output = self.DeclareVectorOutputPort(
            "response_reference", Reference.size(),
            lambda context, output: output.SetFromVector(response_reference(
                self.rules, context.get_discrete_state(self._response).get_value(),
                context.get_time())),
            prerequisites_of_calc={self.discrete_state_ticket(self._response),
                                   self.time_ticket()})

    def _status(self, behaviour: str, context) -> np.ndarray:
        """The status of `behaviour` (`BehaviourStatus`); every field -1 while unconnected."""
        port = self.status_inputs[behaviour]
        return (port.Eval(context) if port.HasValue(context)
                else np.full(BehaviourStatus.size(), -1.0))

    def _leg_now(self, context):
        return LegSignal(context.get_discrete_state(self._leg).get_value())

    def _start_mission(self, context, discrete_state):
        x = self.state_input.Eval(context)
        t = context.get_time()
        leg = LegSignal.zeros()
        leg.start_s = t
        discrete_state.set_value(self._leg, leg[:])
        discrete_state.set_value(self._progress, start_progress(self.legs[0], x))
        watch = Watch.zeros()
        watch.tracking_since_s = -1.0
        watch.position = VehicleState(x).position
        watch.drift_since_s = t
        discrete_state.set_value(self._watch, watch[:])
        discrete_state.set_value(self._heard, np.full(max(len(self.returns_inputs), 1), t))

    def _heard_now(self, context) -> dict:
        """{sensor: the time of its last update with beams (echo or not), s}, updated from the
        returns in `context`."""
        heard = dict(zip(self.returns_inputs,
                         context.get_discrete_state(self._heard).get_value().tolist()))
        for name, port in self.returns_inputs.items():
            if port.HasValue(context):
                returns = port.Eval(context)
                if returns.sequence > 0 and len(returns) > 0:  # beams fired, echo or not
                    heard[name] = max(heard[name], returns.time)
        return heard

    def _watched(self, context, t: float, x: np.ndarray) -> tuple[np.ndarray, bool, bool]:
        """The `watch` group updated at `t` from the reference and the estimate `x`; and
        whether the estimate jumped and the tracking error lasted too long."""
        watch = Watch(context.get_discrete_state(self._watch).get_value().copy())
        position = VehicleState(x).position
        moved = position - watch.position
        jumped = bool(np.linalg.norm(moved) > self.rules.jump_m)
        watch.position = position
        tracking = False
        if self.reference_input.HasValue(context):
            reference = Reference(self.reference_input.Eval(context))
            error = float(np.linalg.norm(position - reference.position))
            since, error0 = watch.tracking_since_s, watch.tracking_error0_m
            if error <= self.rules.tracking_error_m:
                since = -1.0
            elif since < 0 or (t - since >= self.rules.tracking_s
                               and closing(self.rules, error0, error, t - since)):
                since, error0 = t, error  # a new window (or a step being flown: a fresh one)
            tracking = since >= 0 and t - since >= self.rules.tracking_s
            watch.tracking_since_s, watch.tracking_error0_m = since, error0
            # the motion the reference did not command, over windows of tracking_s
            watch.drift = watch.drift + uncommanded(moved, reference.velocity, self.period,
                                                    reference.position - position + moved)
            elapsed = t - watch.drift_since_s
            if elapsed >= self.rules.tracking_s:  # two windows in a row: not a transient
                watch.drift_windows = (watch.drift_windows + 1 if drifting(
                    self.rules, watch.drift, watch.drift_error0_m, error, elapsed) else 0)
                tracking |= watch.drift_windows >= DRIFT_WINDOWS
                watch.drift_since_s, watch.drift_error0_m, watch.drift = t, error, 0.0
        return watch[:], jumped, tracking

    def _respond(self, context, t: float, x: np.ndarray, heard: dict, jumped: bool,
                 tracking: bool, start: float) -> np.ndarray | None:
        """The `response` group after this period's checks, or None to go on with the leg."""
        rules = self.rules
        record = context.get_discrete_state(self._response).get_value()
        response = Response(record)
        mode, cause = RESPONSES[int(response.mode)], CAUSES[int(response.cause)]
        elapsed = t - response.start_s
        position = VehicleState(x).position
        if mode in ("none", "hold"):
            if jumped:
                return response_record("abort", "navigation_jump", t, x, abort_target(rules, x))
            if tracking:
                online = self.map_input.Eval(context) if self.map_input.HasValue(context) else None
                target = back_off_target(rules, x, online.map.occupied_points()
                                         if online is not None else np.zeros((0, 3)))
                if target is None:
                    return response_record("abort", "tracking_error", t, x,
                                           abort_target(rules, x))
                return response_record("back_off", "tracking_error", t, x, target)
        sensors = relied_sensors(self.legs[int(self._leg_now(context).index)].behaviour)
        since = [t - max(heard[s], start) for s in sensors
                 if s in heard and self.returns_inputs[s].HasValue(context)]
        if mode == "none":
            if since and max(since) >= rules.silence_s:
                return response_record("hold", "sonar_silent", t, x, position)
            return None
        if mode == "hold":
            if since and max(since) < rules.silence_s:
                return np.zeros(Response.size())  # the sonar is back: resume the leg
            if elapsed >= rules.hold_max_s:
                return response_record("abort", cause, t, x, abort_target(rules, x))
            return record
        if mode == "back_off":
            if (np.linalg.norm(position - response.target) <= rules.surface_tolerance_m
                    or elapsed >= rules.backoff_max_s):
                return response_record("abort", cause, t, x, abort_target(rules, x))
            return record
        return record  # abort: ended by _update_leg

    def _update_leg(self, context, discrete_state):
        if context.get_discrete_state(self._done)[0]:
            return
        t = context.get_time()
        current = self._leg_now(context)
        index, start = int(current.index), float(current.start_s)
        leg = self.legs[index]
        x = self.state_input.Eval(context)
        watch, jumped, tracking = self._watched(context, t, x)
        heard = self._heard_now(context)
        discrete_state.set_value(self._watch, watch)
        if heard:
            discrete_state.set_value(self._heard, list(heard.values()))
        record = self._respond(context, t, x, heard, jumped, tracking, start)
        if record is not None:
            discrete_state.set_value(self._response, record)
            response = Response(record)
            if RESPONSES[int(response.mode)] != "none":
                if RESPONSES[int(response.mode)] == "abort" and (
                        VehicleState(x).z >= response.z1 - self.rules.surface_tolerance_m
                        or t - response.start_s >= self.rules.abort_max_s):
                    outcomes = context.get_discrete_state(self._outcomes).get_value().copy()
                    outcomes[index] = OUTCOMES.index("aborted")
                    discrete_state.set_value(self._outcomes, outcomes)
                    discrete_state.set_value(self._done, [1.0])
                return  # the leg waits while a response flies
        progress = advance_progress(leg, context.get_discrete_state(self._progress).get_value(),
                                    x)
        outcome = 0
        if goal_reached(leg, index, t, x, progress, self._status(leg.behaviour, context)):
            outcome = 1
        elif t - start >= leg.max_duration:
            outcome = 2
        if outcome:
            outcomes = context.get_discrete_state(self._outcomes).get_value().copy()
            outcomes[index] = outcome
            discrete_state.set_value(self._outcomes, outcomes)
            if index + 1 == len(self.legs):
                discrete_state.set_value(self._done, [1.0])
            else:
                index += 1
                following = LegSignal.zeros()
                following.index, following.start_s = index, t
                discrete_state.set_value(self._leg, following[:])
                progress = start_progress(self.legs[index], x)
        discrete_state.set_value(self._progress, progress)

    def _calc_behaviour(self, context, output):
        if Response(context.get_discrete_state(self._response).get_value()).mode > 0:
            output.set_value(InputPortIndex(self.behaviour_ports["response"]))
            return
        index = int(self._leg_now(context).index)
        output.set_value(InputPortIndex(self.behaviour_ports[self.legs[index].behaviour]))

    def monitor(self, root_context) -> EventStatus:
        """A Simulator monitor: ends the simulation once the last leg is done."""
        if self.GetMyContextFromRoot(root_context).get_discrete_state(self._done)[0]:
            return EventStatus.ReachedTermination(self, "mission complete")
        return EventStatus.Succeeded()

    def flying(self, context) -> Leg | None:
        """The leg flying in this system's `context` (None once the dive is done)."""
        if context.get_discrete_state(self._done)[0]:
            return None
        return self.legs[int(self._leg_now(context).index)]

    def flown_share(self, context, behaviour_share: float | None = None) -> float:
        """How much of the mission is flown, in [0, 1], from this system's `context`: the legs
        ended and the flying leg's share of it (`legs.leg_share`; `behaviour_share`: its
        behaviour's own, used while its status reports this leg), each leg weighing its time
        budget (which is its nominal duration times `limits.time_margin`, plus a slack); 1
        once done."""
        leg = self.flying(context)
        if leg is None:
            return 1.0
        current = self._leg_now(context)
        index = int(current.index)
        if BehaviourStatus(self._status(leg.behaviour, context)).leg != index:
            behaviour_share = None
        share = leg_share(leg, context.get_time() - current.start_s,
                          self.state_input.Eval(context),
                          context.get_discrete_state(self._progress).get_value(),
                          behaviour_share)
        return (self._budgets[index] + share * leg.max_duration) / self._budgets[-1]

    def outcomes(self, context) -> list[str]:
        """Per leg, how it ended (`OUTCOMES`), from this system's `context`."""
        values = context.get_discrete_state(self._outcomes).get_value()
        return [OUTCOMES[int(v)] for v in values]


def responses_from_log(log) -> list[dict]:
    """The responses flown, from a `VectorLog` of the `response` output: per response
    {response, cause, start_s, end_s} (end_s None: still flying when the dive ended)."""
    out = []
    previous = None
    records = Response(log.data().T)
    for t, mode, cause, start in zip(log.sample_times(), records.mode, records.cause,
                                     records.start_s):
        current = (int(mode), int(cause), float(start))
        if current == previous:
            continue
        if out and out[-1]["end_s"] is None:
            out[-1]["end_s"] = float(t)
        if mode > 0:  # a response flies
            out.append(dict(response=RESPONSES[int(mode)], cause=CAUSES[int(cause)],
                            start_s=float(start), end_s=None))
        previous = current
    return out
