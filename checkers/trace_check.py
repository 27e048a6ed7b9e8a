"""An independent check of embodied traces: replay ``trace.json`` against the floor plan's
own files and the task's own PDDL files.

It shares no code with the executor (:mod:`twostep.embodied`) nor with the project's
STRIPS model (:mod:`twostep.plans.simulate`, :mod:`twostep.pddl`): it reads ``kitchen.yaml`` (or
an AI2-THOR layout of the ``alfworld`` wheel) itself, reads the domain and problem files
with its own small s-expression reader, gives every body a copy of the facts of the task
agent it plays (the contract of embodied execution), and replays every applied action in
unified-planning's sequential simulator. It checks that

- bodies start on distinct free cells and every move or backoff is one cell (4-neighbour);
- no body ever stands on a wall, furniture or another body's cell (bodies act one after
  another within a step, so the check is made after every single command);
- waits and interactions do not move a body;
- every applied action is applicable in the simulated state and its effects are the
  simulator's, and each body applies exactly its own plan, in order, once per action;
- after every applied action the body stands on the cell of the location it is at by
  the PDDL (an interaction is made from its object's access cell; a navigation ends there);
- a successful run reaches the goal and ``embodied_length`` is its number of steps.

Real-layout frames: a floor plan record with an ``origin`` ``[x0, z0]`` places grid cell
``(x, y)`` at AI2-THOR grid point ``(x0 + x, z0 - y)`` (0.25 m units; y grows southwards).
"""

from __future__ import annotations

import importlib.util
import re
import warnings
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any

import yaml

Cell = tuple[int, int]
SExpr = str | list["SExpr"]

GRID_M = 0.25  # AI2-THOR's navigation grid, metres


# ------------------------------------------------------------------ s-expressions


def read_sexpr(text: str) -> list[SExpr]:
    """The top-level s-expressions of PDDL ``text``, lower-cased, comments dropped."""
    tokens = re.findall(r"\(|\)|[^\s()]+", re.sub(r";[^\n]*", "", text).lower())
    stack: list[list[SExpr]] = [[]]
    for token in tokens:
        if token == "(":
            stack.append([])
        elif token == ")":
            if len(stack) == 1:
                raise ValueError("unbalanced ')'")
            done = stack.pop()
            stack[-1].append(done)
        else:
            stack[-1].append(token)
    if len(stack) != 1:
        raise ValueError("unbalanced '('")
    return stack[0]


def write_sexpr(expr: SExpr) -> str:
    if isinstance(expr, str):
        return expr
    return "(" + " ".join(write_sexpr(e) for e in expr) + ")"


def _typed_names(items: Sequence[SExpr]) -> list[tuple[str, str]]:
    """``a b - t c`` -> [(a, t), (b, t), (c, object)]."""
    out: list[tuple[str, str]] = []
    pending: list[str] = []
    index = 0
    while index < len(items):
        item = items[index]
        if item == "-" and index + 1 < len(items):
            kind = items[index + 1]
            out += [(name, kind if isinstance(kind, str) else "object") for name in pending]
            pending = []
            index += 2
            continue
        if isinstance(item, str):
            pending.append(item.rstrip(","))
        index += 1
    return out + [(name, "object") for name in pending]


def _section(define: list[SExpr], key: str) -> list[SExpr] | None:
    for part in define:
        if isinstance(part, list) and part and part[0] == key:
            return part
    return None


def _substitute(expr: SExpr, mapping: Mapping[str, str]) -> SExpr:
    if isinstance(expr, str):
        return mapping.get(expr, expr)
    return [_substitute(e, mapping) for e in expr]


def _mentions(expr: SExpr, names: set[str]) -> bool:
    if isinstance(expr, str):
        return expr in names
    return any(_mentions(e, names) for e in expr)


# ------------------------------------------------------------------ the task, per body


@dataclass(frozen=True)
class _Task:
    """A domain and problem as read here: what the replay needs of them."""

    domain: list[SExpr]
    problem: list[SExpr]
    types: Mapping[str, str]  # type -> parent
    objects: Mapping[str, str]  # object -> type
    parameters: Mapping[str, list[tuple[str, str]]]  # action -> [(variable, type)]

    def is_a(self, kind: str, ancestor: str) -> bool:
        seen = set()
        while kind not in seen:
            if kind == ancestor:
                return True
            seen.add(kind)
            kind = self.types.get(kind, kind)
        return False

    def of_type(self, ancestor: str) -> list[str]:
        return sorted(o for o, t in self.objects.items() if self.is_a(t, ancestor))


def _read_task(domain_text: str, problem_text: str) -> _Task:
    (domain,) = [e for e in read_sexpr(domain_text) if isinstance(e, list)]
    (problem,) = [e for e in read_sexpr(problem_text) if isinstance(e, list)]
    types: dict[str, str] = {}
    types_part = _section(domain, ":types")
    for name, parent in _typed_names(types_part[1:] if types_part else []):
        types[name] = parent
    objects: dict[str, str] = {}
    for key, part in ((":constants", _section(domain, ":constants")),
                      (":objects", _section(problem, ":objects"))):  # fmt: skip
        if part is not None and part[0] == key:
            objects.update(_typed_names(part[1:]))
    parameters: dict[str, list[tuple[str, str]]] = {}
    for action in domain:
        if isinstance(action, list) and action and action[0] == ":action":
            params = action[action.index(":parameters") + 1] if ":parameters" in action else []
            parameters[str(action[1])] = _typed_names(params if isinstance(params, list) else [])
    return _Task(domain, problem, types, objects, parameters)


def _body_problem(
    task: _Task, bodies: Mapping[str, str], agent_type: str, constants: Mapping[str, str]
) -> str:
    """The problem with the task's agents replaced by bodies, each a copy of the agent it
    plays (``bodies``: body -> task agent); a goal about an agent holds for its bodies.
    ``constants`` are declared by the domain now, not by the problem."""
    agents = set(task.of_type(agent_type))
    out: list[SExpr] = []
    for part in task.problem:
        if not (isinstance(part, list) and part and part[0] in (":objects", ":init", ":goal")):
            out.append(part)
            continue
        if part[0] == ":objects":
            kept = [
                (o, t) for o, t in _typed_names(part[1:]) if o not in agents and o not in constants
            ]
            kept += [(body, agent_type) for body in bodies]
            items: list[SExpr] = [":objects"]
            for name, kind in kept:
                items += [name, "-", kind]
            out.append(items)
        elif part[0] == ":init":
            facts: list[SExpr] = [":init"]
            facts += [f for f in part[1:] if not _mentions(f, agents)]
            for body, agent in bodies.items():
                facts += [
                    _substitute(f, {agent: body})
                    for f in part[1:]
                    if _mentions(f, {agent}) and not _mentions(f, agents - {agent})
                ]
            out.append(facts)
        else:
            out.append([":goal", _goal_per_body(part[1], bodies, agents)])
    return write_sexpr(out)


def body_problem(
    domain_text: str, problem_text: str, plays: Mapping[str, str], agent_type: str = "agent"
) -> str:
    """The problem's PDDL text with one agent object per body (``plays``: body -> the
    task agent whose facts it copies), for a judge that reads PDDL itself."""
    return _body_problem(_read_task(domain_text, problem_text), plays, agent_type, {})


def who_plays(
    domain_text: str,
    problem_text: str,
    plans: Mapping[str, Sequence[str]],
    agent_type: str = "agent",
) -> dict[str, str]:
    """Which task agent each body plays: the first agent its plan names, when the task
    has it; else the task's first agent (an MA plan's added agent, an empty plan)."""
    task = _read_task(domain_text, problem_text)
    agents = task.of_type(agent_type)
    out = {}
    for body, plan in plans.items():
        out[body] = agents[0]
        for step in plan:
            name, args = _parse_step(step)
            kinds = [k for _, k in task.parameters.get(name, [])]
            named = [a for k, a in zip(kinds, args, strict=False) if task.is_a(k, agent_type)]
            if named:
                out[body] = named[0] if named[0] in agents else agents[0]
                break
    return out


_CONNECTIVES = {"and", "or", "imply"}
_QUANTIFIERS = {"exists", "forall"}


def _goal_per_body(goal: SExpr, bodies: Mapping[str, str], agents: set[str]) -> SExpr:
    """A goal literal about task agent X holds for every body playing X (for every body
    when none plays X); the literal's other terms stay."""
    if isinstance(goal, str) or not goal:
        return goal
    head = goal[0]
    if head in _CONNECTIVES:
        return [head, *[_goal_per_body(g, bodies, agents) for g in goal[1:]]]
    if head in _QUANTIFIERS:
        return [head, goal[1], *[_goal_per_body(g, bodies, agents) for g in goal[2:]]]
    if head == "not":
        inner = goal[1]
        if isinstance(inner, list) and inner and inner[0] not in (*_CONNECTIVES, *_QUANTIFIERS):
            return ["and", *[["not", atom] for atom in _atoms_per_body(inner, bodies, agents)]]
        return ["not", _goal_per_body(inner, bodies, agents)]
    return ["and", *_atoms_per_body(goal, bodies, agents)]


def _atoms_per_body(atom: list[SExpr], bodies: Mapping[str, str], agents: set[str]) -> list[SExpr]:
    named = next((t for t in atom[1:] if isinstance(t, str) and t in agents), None)
    if named is None:
        return [atom]
    playing = [b for b, a in bodies.items() if a == named] or list(bodies)
    return [[atom[0], *[b if t == named else t for t in atom[1:]]] for b in playing]


def _tokens(expr: SExpr) -> set[str]:
    if isinstance(expr, str):
        return {expr}
    return set().union(*(_tokens(e) for e in expr)) if expr else set()


def _domain_constants(task: _Task, actions: Sequence[SExpr]) -> dict[str, str]:
    """Objects the actions name although only the problem declares them (AlfWorld's
    ``SinkBasinType``): they become domain constants."""
    named = set().union(*(_tokens(a) for a in actions)) if actions else set()
    problem_objects = _section(task.problem, ":objects") or [":objects"]
    declared = dict(_typed_names(problem_objects[1:]))
    return {o: declared[o] for o in sorted(named & set(declared))}


def _used_functions(functions: list[SExpr], actions: Sequence[SExpr]) -> list[SExpr]:
    """``:functions`` without those no kept action uses (alfred.pddl's ``distance`` has
    no value in a problem that never sets it, which the simulator refuses)."""
    used = set().union(*(_tokens(a) for a in actions)) if actions else set()
    out: list[SExpr] = [":functions"]
    items = functions[1:]
    for index, item in enumerate(items):
        if isinstance(item, list):
            keep = bool(item) and item[0] in used
            typed = index + 2 < len(items) + 1 and items[index + 1 : index + 2] == ["-"]
            if keep:
                out.append(item)
                if typed:
                    out += items[index + 1 : index + 3]
    return out


def _trimmed_domain(task: _Task, keep: set[str]) -> tuple[str, dict[str, str]]:
    """The domain with only the actions the trace uses (AlfWorld's alfred.pddl has
    actions that do not type-check, e.g. ``(checked ?l)`` for a location), and the
    problem objects it names as constants (declared in the domain here)."""
    actions = [p for p in task.domain if isinstance(p, list) and p and p[0] == ":action"]
    kept_actions = [a for a in actions if a[1] in keep]
    constants = _domain_constants(task, kept_actions)
    parts: list[SExpr] = []
    for part in task.domain:
        if isinstance(part, list) and part and part[0] == ":action" and part[1] not in keep:
            continue
        if isinstance(part, list) and part and part[0] == ":functions":
            part = _used_functions(part, kept_actions)
        if isinstance(part, list) and part and part[0] == ":predicates" and constants:
            items: list[SExpr] = [":constants"]
            for name, kind in constants.items():
                items += [name, "-", kind]
            existing = _section(task.domain, ":constants")
            if existing is None:
                parts.append(items)
            else:
                existing.extend(items[1:])
        parts.append(part)
    return write_sexpr(parts), constants


@lru_cache(maxsize=32)
def _up_problem(domain: str, problem: str) -> Any:
    from unified_planning.io import PDDLReader
    from unified_planning.shortcuts import get_environment

    get_environment().error_used_name = False  # actions named like predicates (open, clean)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return PDDLReader().parse_problem_string(domain, problem)


# ------------------------------------------------------------------ floor plans


@dataclass(frozen=True)
class Floor:
    """Free cells and the cell of every location, in the trace's grid frame."""

    free: frozenset[Cell]
    locations: Mapping[str, Cell]


def read_kitchen_file(path: str | Path) -> Floor:
    """A ``kitchen.yaml`` floor plan file."""
    return read_kitchen(yaml.safe_load(Path(path).read_text()))


def read_kitchen(data: Mapping[str, Any]) -> Floor:
    """A floor plan as ``kitchen.yaml`` holds it: a grid whose walls and furniture
    rectangles block, and the cell of every location."""
    width, height = int(data["width"]), int(data["height"])
    blocked: set[Cell] = set()
    rects = list(data.get("walls") or []) + list((data.get("furniture") or {}).values())
    for x, y, w, h in rects:
        blocked |= {(x + dx, y + dy) for dx in range(w) for dy in range(h)}
    free = {(x, y) for x in range(width) for y in range(height)} - blocked
    locations = {str(k).lower(): (int(v[0]), int(v[1])) for k, v in data["locations"].items()}
    return Floor(frozenset(free), locations)


def alfworld_layouts_folder() -> Path | None:
    """``alfworld/gen/layouts`` of the installed wheel, found without importing it."""
    spec = importlib.util.find_spec("alfworld")
    if spec is None or not spec.submodule_search_locations:
        return None
    folder = Path(next(iter(spec.submodule_search_locations))) / "gen" / "layouts"
    return folder if folder.is_dir() else None


_DEMANGLE = (("_bar_", "|"), ("_minus_", "-"), ("_plus_", "+"), ("_dot_", "."))


def _grid_point(location: str) -> Cell | None:
    name = location.lower()
    for mangled, plain in _DEMANGLE:
        name = name.replace(mangled, plain)
    parts = name.split("|")
    if len(parts) < 3 or parts[0] != "loc":
        return None
    return int(parts[1]), int(parts[2])


def read_layout(name: str, origin: Sequence[int], locations: Sequence[str]) -> Floor:
    """An AI2-THOR layout (``FloorPlanN-layout.npy``: reachable points in metres) in the
    trace's frame, and the cells of AlfWorld location names on it."""
    import numpy as np

    folder = alfworld_layouts_folder()
    if folder is None:
        raise FileNotFoundError("the alfworld wheel is not installed (pip extra 'embodied')")
    points = np.load(folder / f"{name}-layout.npy")
    x0, z0 = int(origin[0]), int(origin[1])

    def to_grid(point: Cell) -> Cell:
        return point[0] - x0, z0 - point[1]

    free = {
        to_grid((round(float(x) / GRID_M), round(float(z) / GRID_M))) for x, z in points.tolist()
    }
    cells = {}
    for location in locations:
        point = _grid_point(location)
        if point is not None:
            cells[location] = to_grid(point)
    return Floor(frozenset(free), cells)


# ------------------------------------------------------------------ the replay


@dataclass
class TraceReport:
    """What the replay found: counts and one line per violation."""

    steps: int = 0
    commands: int = 0
    moves: int = 0
    interactions: int = 0
    navigations: int = 0
    out_of_reach: int = 0
    violations: list[str] = field(default_factory=list)
    kinds: Counter[str] = field(default_factory=Counter)

    @property
    def ok(self) -> bool:
        return not self.violations

    def flag(self, kind: str, message: str) -> None:
        self.kinds[kind] += 1
        self.violations.append(f"{kind}: {message}")


def _parse_step(text: str) -> tuple[str, list[str]]:
    (expr,) = read_sexpr(text)
    assert isinstance(expr, list) and all(isinstance(e, str) for e in expr)
    return str(expr[0]), [str(e) for e in expr[1:]]


def check_trace(
    record: Mapping[str, Any],
    plans: Mapping[str, Sequence[str]],
    domain_text: str,
    problem_text: str,
    floor: Floor | None = None,
    agent_type: str = "agent",
    location_type: str = "location",
) -> TraceReport:
    """Replay one embodied trace record (the content of ``trace.json``: ``trace``,
    ``start_positions``, ``status``, ``embodied_length`` and the ``floor_plan`` it names).

    ``plans`` are the bodies' plans in the task's own terms (result.json's ``plans``),
    ``domain_text`` and ``problem_text`` the task's PDDL files;
    ``floor`` is the floor plan read from its source (default: the layout named in the
    record, from the alfworld wheel).
    """
    from unified_planning.shortcuts import SequentialSimulator

    task = _read_task(domain_text, problem_text)
    locations = set(task.of_type(location_type))
    if floor is None:
        plan_record = record["floor_plan"]
        floor = read_layout(str(plan_record["layout"]), plan_record["origin"], sorted(locations))
    report = TraceReport()
    starts = {str(b): (int(c[0]), int(c[1])) for b, c in record["start_positions"].items()}
    bodies = list(starts)

    playing = who_plays(
        domain_text, problem_text, {b: plans.get(b, ()) for b in bodies}, agent_type
    )
    used = {_parse_step(s)[0] for plan in plans.values() for s in plan}
    domain, constants = _trimmed_domain(task, used)
    up = _up_problem(domain, _body_problem(task, playing, agent_type, constants))
    where = {p.name for p in up.fluents if len(p.signature) == 2}
    at_fluents = [
        up.fluent(name)
        for name in sorted(where)
        if task.is_a(up.fluent(name).signature[0].type.name, agent_type)
        and task.is_a(up.fluent(name).signature[1].type.name, location_type)
    ]

    position = dict(starts)
    if len(set(starts.values())) != len(starts):
        report.flag("collision", f"two bodies start on one cell: {starts}")
    for body, cell in starts.items():
        if cell not in floor.free:
            report.flag("blocked", f"{body} starts on {cell}, not a free cell")

    todo = {body: list(plans.get(body, ())) for body in bodies}
    done_in_step: set[tuple[int, str]] = set()
    last_step = 0
    with SequentialSimulator(problem=up) as simulator:
        state = simulator.get_initial_state()

        def located_at(body: str, candidates: Sequence[str]) -> list[str]:
            out = []
            for location in candidates:
                for fluent in at_fluents:
                    value = state.get_value(fluent(up.object(body), up.object(location)))
                    if value.bool_constant_value():
                        out.append(location)
            return out

        for entry in record["trace"]:
            step, body, primitive = int(entry["step"]), str(entry["agent"]), entry["primitive"]
            cell = (int(entry["position"][0]), int(entry["position"][1]))
            report.commands += 1
            if step < last_step or step > last_step + 1:
                report.flag("steps", f"step {step} after step {last_step}")
            last_step = max(last_step, step)
            if (step, body) in done_in_step:
                report.flag("steps", f"{body} acts twice in step {step}")
            done_in_step.add((step, body))
            if body not in position:
                report.flag("steps", f"step {step}: unknown body {body}")
                continue
            before = position[body]
            distance = abs(cell[0] - before[0]) + abs(cell[1] - before[1])
            applied = entry.get("applied")
            if primitive == "backoff" and distance != 1:
                report.flag("move", f"step {step} {body}: backoff of {distance} cells")
            elif primitive == "move" and (distance > 1 or (distance == 0 and not applied)):
                report.flag("move", f"step {step} {body}: move of {distance} cells")
            elif primitive in ("wait", "interact") and distance:
                report.flag("move", f"step {step} {body}: {primitive} moves {distance} cells")
            if distance and primitive in ("move", "backoff"):
                report.moves += 1
            if cell not in floor.free:
                report.flag("blocked", f"step {step} {body} on {cell}: wall or furniture")
            others = {b: c for b, c in position.items() if b != body}
            if cell in others.values():
                report.flag("collision", f"step {step} {body} on {cell} with another body")
            position[body] = cell
            if not applied:
                continue
            expected = todo[body].pop(0) if todo[body] else None
            if entry.get("action") != expected:
                report.flag(
                    "plan", f"step {step} {body}: {entry.get('action')} (plan says {expected})"
                )
            name, args = _parse_step(str(applied))
            if expected is not None:
                source_name, source_args = _parse_step(expected)
                renamed = [
                    body if i < len(task.parameters.get(name, [])) and task.is_a(
                        task.parameters[name][i][1], agent_type) else a
                    for i, a in enumerate(source_args)
                ]  # fmt: skip
                if (source_name, renamed) != (name, args):
                    report.flag("plan", f"step {step} {body}: applied {applied} for {expected}")
            try:
                action = up.action(name)
                objects = [up.object(a) for a in args]
            except Exception:
                report.flag("pddl", f"step {step} {body}: {applied} is not an action of the task")
                continue
            if not simulator.is_applicable(state, action, objects):
                unmet, _ = simulator.get_unsatisfied_conditions(state, action, objects)
                report.flag("pddl", f"step {step} {body}: {applied} not applicable ({unmet})")
                continue
            state = simulator.apply(state, action, objects)
            params = task.parameters.get(name, [])
            named = [
                a for (_, k), a in zip(params, args, strict=False) if task.is_a(k, location_type)
            ]
            here = located_at(body, named or sorted(locations))
            navigation = primitive == "move"
            report.navigations += navigation
            report.interactions += not navigation
            if not here:
                report.flag("reach", f"step {step} {body}: {applied} leaves it at no location")
                report.out_of_reach += not navigation
                continue
            cells = {floor.locations.get(loc) for loc in here}
            if cell not in cells:
                report.out_of_reach += not navigation
                report.flag(
                    "reach",
                    f"step {step} {body} at {cell}: {applied} needs it at "
                    f"{', '.join(f'{loc} {floor.locations.get(loc)}' for loc in here)}",
                )
        report.steps = last_step
        for body, left in todo.items():
            if left and record.get("status") == "success":
                report.flag("plan", f"{body} never applied {left[0]}")
        if record.get("status") == "success":
            if not simulator.is_goal(state):
                report.flag("goal", "the run says success but the goal does not hold")
            if record.get("embodied_length") != last_step:
                report.flag(
                    "length",
                    f"embodied_length {record.get('embodied_length')} but {last_step} steps",
                )
    return report
