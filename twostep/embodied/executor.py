"""Asynchronous multi-agent execution of PDDL plans on a grid kitchen (the paper's Table II).

The rules follow the paper's AI2-THOR setup, on our own grid (AI2-THOR needs a Unity
binary that cannot run here):

- every planning agent is a body on the floor plan, starting on a seeded random free cell;
- at every environment step each agent, one after another in hand-off order, issues one
  command: a navigation move, an interaction, or a wait (a no-op);
- a navigation action (any action that puts the agent at another location, e.g.
  ``goto``) takes as many moves as the shortest path around walls, furniture and the
  other agents' current cells; the agent's later actions queue behind it;
- an action whose preconditions do not hold yet makes the agent wait;
- an agent that is done and stands in a blocked agent's way steps aside at once (to the
  nearest cell off every working agent's way);
- when nobody can make progress while someone's way is blocked (or an agent has been
  blocked for ``stall_limit`` steps), one of the agents involved, chosen at random, backs
  off to a random reachable cell nearby, and then everyone retries;
- a step budget turns an execution that can never finish into a recorded failure.

Every interaction, and every navigation action when the agent arrives, is applied to one
shared grounded STRIPS state (:class:`twostep.plans.simulate.Grounder`): an action runs only when
its preconditions hold, so the trace is a valid sequential plan of the task with one
agent object per body. Execution length = environment steps until every agent is done.

Input plans name the task's own agent object (SA and TwoStep plans all name, e.g.,
``alice``): every argument in an agent-typed parameter position is renamed to the body
executing the plan, and each body starts from a copy of that agent's initial facts.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from random import Random
from typing import Any

from twostep.embodied.floorplan import Cell, FloorPlan
from twostep.embodied.navigation import reachable_cells, shortest_path
from twostep.embodied.scene import Scene, scene_of
from twostep.pddl import Fact, Goal, Problem
from twostep.plans.simulate import GroundAction, Grounder, PlanError, parse_action
from twostep.util.outcome import EmbodiedStatus as EmbodiedStatus

AGENT_TYPE = "agent"
LOCATION_TYPE = "location"

PRIMITIVES = ("move", "interact", "wait", "backoff")


SUCCESS = EmbodiedStatus.SUCCESS
DEADLOCK = EmbodiedStatus.DEADLOCK
BOXED_IN = EmbodiedStatus.BOXED_IN
UNREACHABLE = EmbodiedStatus.UNREACHABLE
NO_CELL = EmbodiedStatus.NO_CELL
BUDGET_EXCEEDED = EmbodiedStatus.BUDGET_EXCEEDED
INVALID_PLAN = EmbodiedStatus.INVALID_PLAN
GOAL_NOT_REACHED = EmbodiedStatus.GOAL_NOT_REACHED


def failure_line(status: str, step: int | None, agent: str | None) -> str | None:
    """The one-line verdict of a failed execution (``embodied_failed: boxed_in at step 12,
    agent1``), or None for a success."""
    if status == EmbodiedStatus.SUCCESS:
        return None
    where = "" if step is None else f" at step {step}"
    who = "" if agent is None else f", {agent}"
    return f"embodied_failed: {status}{where}{who}"


class EmbodiedError(Exception):
    """A task that cannot be embodied at all (e.g. a domain without an agent type)."""


@dataclass(frozen=True)
class ExecutorSettings:
    """Knobs of one embodied execution."""

    seed: int = 0
    max_steps: int | None = None  # None: 200 + 50 steps per plan action
    # Several bodies start on seeded random free cells (False: on their PDDL start
    # location's cell, or the nearest free one). A single body (SA, or a TwoStep run
    # without helpers) always starts on its start location's cell: the paper's SA has no
    # variance.
    random_start: bool = True
    stall_limit: int = 4  # blocked this many steps in a row -> back off even if others move
    backoff_radius: int = 4  # backoff destinations are at most this many moves away
    location_type: str = LOCATION_TYPE
    agent_type: str = AGENT_TYPE


@dataclass(frozen=True)
class TraceStep:
    """What one agent did in one environment step."""

    step: int
    agent: str
    primitive: str  # move | interact | wait | backoff
    position: Cell  # after the step
    action: str | None = None  # the plan action being worked on, in the plan's own terms
    applied: str | None = None  # the ground action applied now, in execution terms
    holding: tuple[str, ...] = ()
    reason: str | None = None  # why the agent waited
    scene: Scene | None = None  # the scene after this step, when the step changed it

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "step": self.step,
            "agent": self.agent,
            "primitive": self.primitive,
            "position": list(self.position),
        }
        if self.action is not None:
            out["action"] = self.action
        if self.applied is not None:
            out["applied"] = self.applied
        if self.holding:
            out["holding"] = list(self.holding)
        if self.reason is not None:
            out["reason"] = self.reason
        if self.scene is not None:
            out["scene"] = self.scene.to_dict()
        return out


@dataclass
class EmbodiedResult:
    """The outcome of one embodied execution; :meth:`to_dict` is the result.json shape."""

    status: str
    agents: list[str]
    embodied_length: int | None
    steps: int
    waits: int
    backoffs: int
    trace: list[TraceStep]
    start_positions: dict[str, Cell]
    floor_plan: str
    seed: int
    agent: str | None = None  # on failure: which agent, at which step, and why
    step: int | None = None
    reason: str = ""
    unmet_goal: list[str] = field(default_factory=list)
    problem: Problem | None = field(default=None, repr=False)  # the task with one agent per body
    scene: Scene = field(default_factory=Scene)  # at the start (steps record its changes)

    @property
    def success(self) -> bool:
        return self.status == SUCCESS

    @property
    def failure(self) -> str | None:
        """None for a success, else the one-line verdict (:func:`failure_line`)."""
        return failure_line(self.status, self.step, self.agent)

    @property
    def message(self) -> str:
        if self.success:
            return (
                f"embodied execution: {self.embodied_length} steps, {self.waits} waits, "
                f"{self.backoffs} backoffs"
            )
        where = f" ({self.agent}, step {self.step})" if self.agent is not None else ""
        return f"embodied execution failed: {self.status}{where}: {self.reason}"

    def to_dict(self, include_trace: bool = False) -> dict[str, Any]:
        out: dict[str, Any] = {
            "status": self.status,
            "embodied_length": self.embodied_length,
            "steps": self.steps,
            "waits": self.waits,
            "backoffs": self.backoffs,
            "agents": self.agents,
            "start_positions": {a: list(c) for a, c in self.start_positions.items()},
            "floor_plan": self.floor_plan,
            "seed": self.seed,
            "agent": self.agent,
            "step": self.step,
            "reason": self.reason,
            "unmet_goal": self.unmet_goal,
        }
        if include_trace:
            out["trace"] = [t.to_dict() for t in self.trace]
        return out


# ------------------------------------------------------------------ bodies


def _objects_of_type(problem: Problem, type_name: str) -> list[str]:
    domain = problem.domain
    return sorted(o for o, t in problem.all_objects.items() if domain.is_subtype(t, type_name))


def body_names(names: Sequence[str], taken: Mapping[str, str]) -> list[str]:
    """The bodies' object names: the run's agent names, suffixed if the task uses them."""
    out = []
    for name in names:
        body = name.lower()
        while body in taken or body in out:
            body += "-body"
        out.append(body)
    return out


@dataclass(frozen=True)
class Embodiment:
    """The task with one agent object per body, and each body's plan in its terms."""

    problem: Problem
    bodies: tuple[str, ...]
    plans: tuple[tuple[str, ...], ...]
    sources: tuple[tuple[str, ...], ...]  # the same plans as given


def embody(
    problem: Problem,
    plans: Sequence[Sequence[str]],
    names: Sequence[str],
    agent_type: str = AGENT_TYPE,
) -> Embodiment:
    """Give each plan a body: rename agent arguments, copy the agent's initial facts.

    A plan's agent is the first agent-typed argument it names; a body whose plan names an
    agent the task does not have (an MA plan's added agent) or no agent at all starts as
    a copy of the task's first agent. Goal literals about the task's agents must hold for
    every body that plays that agent.
    """
    domain = problem.domain
    agents = _objects_of_type(problem, agent_type)
    if not agents:
        raise EmbodiedError(
            f"domain {domain.name} has no objects of type '{agent_type}': embodied execution "
            "needs actions that name the acting agent"
        )
    agent_slots = {
        name: [i for i, (_, t) in enumerate(a.parameters) if domain.is_subtype(t, agent_type)]
        for name, a in domain.actions.items()
    }
    agent_set = set(agents)
    # bodies replace the task's agent objects, so only the other objects' names are taken
    bodies = body_names(names, {o: t for o, t in problem.all_objects.items() if o not in agent_set})
    renamed: list[tuple[str, ...]] = []
    templates: list[str] = []
    for plan, body in zip(plans, bodies, strict=True):
        template: str | None = None
        out = []
        for step in plan:
            name, args = parse_action(step)
            slots = agent_slots.get(name, [])
            new_args = list(args)
            for i in slots:
                if i < len(args):
                    template = template or args[i]
                    new_args[i] = body
            out.append("(" + " ".join((name, *new_args)) + ")")
        renamed.append(tuple(out))
        templates.append(template if template in agents else agents[0])

    def mentions_agent(fact: Fact) -> bool:
        return any(term in agent_set for term in fact[1:])

    init = {f for f in problem.init if not mentions_agent(f)}
    for body, template in zip(bodies, templates, strict=True):
        init |= {
            tuple(body if term == template else term for term in f)
            for f in problem.init
            if template in f[1:]
        }

    bodies_of = {agent: [b for b, t in zip(bodies, templates, strict=True) if t == agent]
                 for agent in agents}  # fmt: skip

    def per_body(facts: frozenset[Fact]) -> frozenset[Fact]:
        """A literal about agent X holds for each body playing X (or every body, if none)."""
        out: set[Fact] = set()
        for fact in facts:
            named = [t for t in fact[1:] if t in agent_set]
            if not named:
                out.add(fact)
                continue
            for body in bodies_of[named[0]] or bodies:
                out.add(tuple(body if term in agent_set else term for term in fact))
        return frozenset(out)

    objects = {o: t for o, t in problem.objects.items() if o not in agent_set}
    objects.update({body: agent_type for body in bodies})
    embodied = Problem(
        f"{problem.name}-embodied",
        domain,
        objects,
        frozenset(init),
        Goal(per_body(problem.goal.positive), per_body(problem.goal.negative)),
        problem.source,
    )
    return Embodiment(embodied, tuple(bodies), tuple(renamed), tuple(tuple(p) for p in plans))


# ------------------------------------------------------------------ execution


@dataclass
class _Body:
    name: str
    plan: list[GroundAction]
    source: tuple[str, ...]  # each step as its plan names it (the task's own terms)
    targets: list[Cell | None]  # the cell a navigation action walks to, None otherwise
    position: Cell
    index: int = 0
    path: list[Cell] = field(default_factory=list)
    backoff: list[Cell] = field(default_factory=list)
    blocked_for: int = 0
    holding: tuple[str, ...] = ()
    walking_to: Cell | None = None  # the cell of the current walk (a navigation, a way back)

    @property
    def done(self) -> bool:
        return self.index >= len(self.plan)


class _Failure(Exception):
    def __init__(self, status: str, agent: str | None, step: int, reason: str):
        super().__init__(reason)
        self.status, self.agent, self.step, self.reason = status, agent, step, reason


def _navigation_target(action: GroundAction, body: str, locations: set[str]) -> str | None:
    """The location a navigation action puts ``body`` at, or None for an interaction."""
    for fact in action.possible_add:
        if body in fact[1:]:
            for term in fact[1:]:
                if term in locations:
                    return term
    return None


class _Execution:
    def __init__(
        self,
        embodiment: Embodiment,
        floor_plan: FloorPlan,
        settings: ExecutorSettings,
    ):
        self.floor_plan = floor_plan
        self.settings = settings
        self.rng = Random(settings.seed)
        self.problem = embodiment.problem
        self.state = set(self.problem.init)
        self.locations = set(_objects_of_type(self.problem, settings.location_type))
        self.trace: list[TraceStep] = []
        self.waits = 0
        self.backoffs = 0
        self.step = 0
        self.bodies: list[_Body] = []
        self._connections: dict[tuple[Cell, Cell], bool] = {}
        self._where: dict[str, str | None] = {}  # body -> its location (see _location_of)
        grounder = Grounder(self.problem)
        for body, plan, source in zip(
            embodiment.bodies, embodiment.plans, embodiment.sources, strict=True
        ):
            try:
                grounded = grounder.ground_plan(plan)
            except PlanError as error:
                raise _Failure(INVALID_PLAN, body, 0, str(error)) from None
            targets: list[Cell | None] = []
            for action in grounded:
                location = _navigation_target(action, body, self.locations)
                cell = None if location is None else floor_plan.cell_of(location)
                if location is not None and cell is None:
                    raise _Failure(
                        NO_CELL,
                        body,
                        0,
                        f"location {location} (in {action}) has no cell in floor plan "
                        f"{floor_plan.name}",
                    )
                targets.append(cell)
            self.bodies.append(_Body(body, grounded, source, targets, (-1, -1)))
        self._place_bodies()
        self.start_cells = [b.position for b in self.bodies]
        for placed in self.bodies:
            placed.holding = self._held(placed.name)
        self.scene = self.start_scene = scene_of(self.state)

    # ---------------------------------------------------------------- set-up

    def _place_bodies(self) -> None:
        free = self.floor_plan.free_cells()
        if len(free) < len(self.bodies):
            raise _Failure(
                BOXED_IN,
                self.bodies[len(free)].name,
                0,
                f"{len(self.bodies)} agents but {len(free)} free cells on "
                f"{self.floor_plan.name}: {self.bodies[len(free)].name} has nowhere to stand",
            )
        if self.settings.random_start and len(self.bodies) > 1:
            for body, cell in zip(
                self.bodies, self.rng.sample(free, len(self.bodies)), strict=True
            ):
                body.position = cell
            return
        taken: set[Cell] = set()
        for body in self.bodies:
            start = (
                next(
                    (
                        self.floor_plan.cell_of(f[2])
                        for f in sorted(self.state)
                        if len(f) == 3 and f[1] == body.name and f[2] in self.locations
                    ),
                    None,
                )
                or free[0]
            )
            distances = reachable_cells(self.floor_plan, start)
            # the start cell, else the nearest free one (two bodies of one PDDL agent)
            cell = min(
                (c for c in [start, *distances] if c not in taken),
                key=lambda c: (distances.get(c, 0), c),
                default=next(c for c in free if c not in taken),
            )
            body.position = cell
            taken.add(cell)

    def _held(self, body: str) -> tuple[str, ...]:
        """What ``body`` holds: the non-location objects of its own facts."""
        return tuple(
            sorted(
                term
                for f in self.state
                if body in f[1:]
                for term in f[1:]
                if term != body and term not in self.locations
            )
        )

    # ---------------------------------------------------------------- stepping

    def _occupied(self, but: _Body) -> set[Cell]:
        return {b.position for b in self.bodies if b is not but}

    def _record(self, body: _Body, primitive: str, **kwargs: Any) -> None:
        self.trace.append(
            TraceStep(
                self.step, body.name, primitive, body.position, holding=body.holding, **kwargs
            )
        )

    def _apply(self, body: _Body, action: GroundAction) -> None:
        self.state = set(action.apply(frozenset(self.state)))  # conditional effects, axioms
        if any(body.name in f[1:] for f in action.possible_add | action.possible_delete):
            body.holding = self._held(body.name)
            self._where.pop(body.name, None)
        body.index += 1
        body.path = []

    def _act(self, body: _Body) -> str:
        """One command of ``body``; returns 'progress', 'blocked', 'waiting' or 'idle'."""
        if body.backoff:
            nxt = body.backoff[0]
            if nxt in self._occupied(body):
                body.backoff = []  # someone stepped in: give up the backoff, retry the plan
            else:
                body.backoff.pop(0)
                body.position = nxt
                self._record(body, "backoff")
                return "progress"
        if body.done:
            return "idle"
        action = body.plan[body.index]
        source = body.source[body.index]
        target = body.targets[body.index]
        if target is None:
            # An interaction is made from the cell of the location the body is at; a body
            # moved off it (a backoff, a random start) walks back first (queued navigation).
            home = self._home(body, source)
            if body.position != home:
                return self._walk(body, home, source, arrival=False)
        missing = action.failing_precondition(self.state)
        if missing is not None:
            self.waits += 1
            self._record(body, "wait", action=source, reason=f"precondition {missing}")
            return "waiting"
        if target is None:
            self._apply(body, action)
            scene = scene_of(self.state)
            changed, self.scene = scene != self.scene, scene
            self._record(
                body,
                "interact",
                action=source,
                applied=str(action),
                scene=scene if changed else None,
            )
            return "progress"
        if body.position != target:
            outcome = self._walk(body, target, source, arrival=True)
            if body.position != target:
                return outcome
        self._apply(body, action)
        self._record(body, "move", action=source, applied=str(action))
        return "progress"

    def _home(self, body: _Body, source: str) -> Cell:
        """The cell of the location ``body`` is at by the PDDL state."""
        location = self._location_of(body.name)
        cell = None if location is None else self.floor_plan.cell_of(location)
        if cell is None:
            raise _Failure(
                NO_CELL,
                body.name,
                self.step,
                f"{source}: {body.name} is at "
                f"{location or 'no location'}, which has no cell in floor plan "
                f"{self.floor_plan.name}",
            )
        return cell

    def _location_of(self, body: str) -> str | None:
        """The location ``body`` is at by the state (the first, should it be at several);
        kept until an action about the body applies."""
        if body not in self._where:
            at = sorted(
                t for f in self.state if body in f[1:] for t in f[1:] if t in self.locations
            )
            self._where[body] = at[0] if at else None
        return self._where[body]

    def _walk(self, body: _Body, target: Cell, source: str, arrival: bool) -> str:
        """One move of ``body`` along a shortest free path to ``target`` (re-planned when
        someone steps into it): 'progress', or 'blocked' (a wait) when agents bar the way.
        ``arrival``: the caller records the move that reaches ``target`` (it applies the
        navigation action there)."""
        body.walking_to = target
        occupied = self._occupied(body)
        if not body.path or body.path[-1] != target or body.path[0] in occupied:
            path = shortest_path(self.floor_plan, body.position, target, occupied)
            if path is None:
                if not self._connected(body.position, target):
                    raise _Failure(
                        UNREACHABLE,
                        body.name,
                        self.step,
                        f"{source}: cell {target} cannot be reached from {body.position} "
                        "(walls or furniture cut it off)",
                    )
                self.waits += 1
                blockers = self._blockers(body, target)
                self._record(
                    body,
                    "wait",
                    action=source,
                    reason=f"way to {target} blocked by {', '.join(blockers) or 'agents'}",
                )
                return "blocked"
            body.path = path
        body.position = body.path.pop(0)
        if body.position != target or not arrival:
            self._record(body, "move", action=source)
        return "progress"

    def _connected(self, start: Cell, goal: Cell) -> bool:
        """Whether walls and furniture (agents aside) leave a way from start to goal."""
        key = (start, goal)
        if key not in self._connections:
            self._connections[key] = shortest_path(self.floor_plan, start, goal) is not None
        return self._connections[key]

    def _free_path(self, body: _Body) -> list[Cell]:
        """The way ``body`` walks (agents aside); none once it is done."""
        if body.done or body.walking_to is None:
            return []
        return shortest_path(self.floor_plan, body.position, body.walking_to) or []

    def _blockers(self, body: _Body, target: Cell) -> list[str]:
        cells = set(self._free_path(body)) | {target}
        return [b.name for b in self.bodies if b is not body and b.position in cells]

    def _make_way(self, blocked: list[_Body]) -> bool:
        """Bodies that are done and stand in a blocked body's way step aside at once, to
        the nearest cell off every working body's way (a backoff of an idle body: it has
        nothing left to do, so no random choice is needed). False if there is none."""
        ways: set[Cell] = set()
        for body in blocked:
            ways |= set(self._free_path(body))
            if body.walking_to is not None:
                ways.add(body.walking_to)
        idle = [b for b in self.bodies if b.done and not b.backoff and b.position in ways]
        if not idle:
            return False
        busy: set[Cell] = set()
        for body in self.bodies:
            if not body.done:
                busy |= set(self._free_path(body))
        moved = False
        for body in idle:
            distances = reachable_cells(self.floor_plan, body.position, self._occupied(body))
            aside = [c for c in distances if c not in ways | busy]
            if not aside:
                continue
            destination = min(aside, key=lambda c: (distances[c], c))
            body.backoff = (
                shortest_path(self.floor_plan, body.position, destination, self._occupied(body))
                or []
            )
            self.backoffs += 1
            moved = True
        return moved

    def _back_off(self, blocked: list[_Body]) -> None:
        """One agent involved in the jam moves to a random reachable cell nearby."""
        paths = {b.name: set(self._free_path(b)) for b in blocked}
        jam = set().union(*paths.values())
        candidates = {b.name for b in blocked}
        candidates |= {b.name for b in self.bodies if b.position in jam}
        order = sorted(candidates)
        self.rng.shuffle(order)
        by_name = {b.name: b for b in self.bodies}
        for name in order:
            body = by_name[name]
            distances = reachable_cells(self.floor_plan, body.position, self._occupied(body))
            near = sorted(c for c, d in distances.items() if 0 < d <= self.settings.backoff_radius)
            if not near:
                continue
            aside = [c for c in near if c not in jam]
            destination = self.rng.choice(aside or near)
            path = shortest_path(self.floor_plan, body.position, destination, self._occupied(body))
            body.backoff = path or []
            body.path = []
            self.backoffs += 1
            for b in self.bodies:
                b.blocked_for = 0
            return
        first = blocked[0]
        raise _Failure(
            BOXED_IN,
            first.name,
            self.step,
            f"{first.source[first.index]}: the way is blocked by "
            f"{', '.join(self._blockers(first, first.walking_to or first.position))}"
            " and no agent can make way",
        )

    def run(self, max_steps: int) -> None:
        while not all(b.done for b in self.bodies):
            if self.step >= max_steps:
                late = next(b for b in self.bodies if not b.done)
                raise _Failure(
                    BUDGET_EXCEEDED,
                    late.name,
                    self.step,
                    f"step budget of {max_steps} exhausted with "
                    f"{late.source[late.index]} still to do",
                )
            self.step += 1
            progressed = False
            blocked: list[_Body] = []
            waiting: list[_Body] = []
            for body in self.bodies:
                outcome = self._act(body)
                if outcome == "progress":
                    progressed = True
                    body.blocked_for = 0
                elif outcome == "blocked":
                    body.blocked_for += 1
                    blocked.append(body)
                elif outcome == "waiting":
                    waiting.append(body)
            if blocked and self._make_way(blocked):
                progressed = True
            elif (blocked and not progressed) or any(
                b.blocked_for >= self.settings.stall_limit for b in blocked
            ):
                self._back_off(blocked)
            elif not progressed and waiting:
                first = waiting[0]
                reasons = "; ".join(
                    f"{b.name} waits for {b.plan[b.index].failing_precondition(self.state)} "
                    f"of {b.source[b.index]}"
                    for b in waiting
                )
                raise _Failure(
                    DEADLOCK,
                    first.name,
                    self.step,
                    f"no agent can make progress any more: {reasons}",
                )


def default_budget(plans: Sequence[Sequence[str]]) -> int:
    return 200 + 50 * sum(len(p) for p in plans)


def execute(
    problem: Problem,
    plans: Sequence[Sequence[str]],
    floor_plan: FloorPlan,
    names: Sequence[str] | None = None,
    settings: ExecutorSettings | None = None,
) -> EmbodiedResult:
    """Execute per-agent plans (hand-off order) on ``floor_plan``; never raises on bad plans.

    ``names`` labels the agents (default ``agent0..``); failures come back as a status
    with the agent, the step and the reason.
    """
    settings = settings or ExecutorSettings()
    names = list(names) if names is not None else [f"agent{i}" for i in range(len(plans))]
    if len(names) != len(plans):
        raise ValueError(f"{len(plans)} plans but {len(names)} agent names")
    embodiment = embody(problem, plans, names, settings.agent_type)
    budget = settings.max_steps if settings.max_steps is not None else default_budget(plans)
    execution: _Execution | None = None
    failure: _Failure | None = None
    try:
        execution = _Execution(embodiment, floor_plan, settings)
        execution.run(budget)
    except _Failure as error:
        failure = error
    bodies = list(embodiment.bodies)
    result = EmbodiedResult(
        status=SUCCESS,
        agents=bodies,
        embodied_length=None,
        steps=execution.step if execution else 0,
        waits=execution.waits if execution else 0,
        backoffs=execution.backoffs if execution else 0,
        trace=execution.trace if execution else [],
        start_positions={},
        floor_plan=floor_plan.name,
        seed=settings.seed,
        problem=embodiment.problem,
    )
    if execution is not None:
        result.start_positions = dict(zip(bodies, execution.start_cells, strict=True))
        result.scene = execution.start_scene
    if failure is not None:
        result.status, result.agent, result.step, result.reason = (
            failure.status,
            failure.agent,
            failure.step,
            failure.reason,
        )
        return result
    assert execution is not None
    goal = embodiment.problem.goal
    if not goal.holds(frozenset(execution.state)):
        result.status = GOAL_NOT_REACHED
        result.step = execution.step
        result.unmet_goal = goal.unmet(frozenset(execution.state))
        result.reason = "the plans ran to the end but the goal does not hold: " + ", ".join(
            result.unmet_goal
        )
        return result
    result.embodied_length = execution.step
    return result


def execute_plans(
    problem: Problem,
    plans: Mapping[str, Sequence[str]],
    agent_order: Sequence[str],
    floor_plan: FloorPlan,
    settings: ExecutorSettings | None = None,
) -> EmbodiedResult:
    """Execute a run's plans (``plans`` by agent, in the terms of ``problem``, with
    ``agent_order``; agents without a plan are left out); a failure is the result's
    status, never raised."""
    order = [agent for agent in agent_order if agent in plans]
    return execute(problem, [plans[a] for a in order], floor_plan, order, settings)
