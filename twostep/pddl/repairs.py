"""Repairs of real-world PDDL quirks, made on s-expressions before anything reads the task.

Three quirks of files that are otherwise read as they are:

- **Objects only the problem declares.** The LLM+P tyreworld domain mentions ``wrench``,
  ``jack`` and ``pump`` in its actions, AlfWorld's ``alfred.pddl`` mentions
  ``SinkBasinType`` and ``MicrowaveType``, while only the problems declare them; Fast
  Downward rejects that ("Undefined object"). They become typed constants of the domain
  (and leave the problem's objects), which keeps the meaning.
- **Objects both files declare.** The LLM+P tyreworld problems declare ``wrench``,
  ``jack`` and ``pump`` as objects; a domain that already declares them as constants (ours
  does) meets them twice, and Fast Downward rejects the duplicates. A problem object that
  is a domain constant of the same type (or that the problem leaves untyped or types as
  ``object``) is the same object: it leaves the problem's objects. A problem that gives it
  another type contradicts the domain: a :class:`~twostep.pddl.errors.PDDLError` naming the
  file, the object and both types.
- **Commas in variable lists.** AlfWorld writes ``(?l - location, ?r - receptacle)``;
  Fast Downward would read ``location,`` as a type of no objects and silently make the
  action impossible. A comma is no part of a PDDL name: it is dropped.

Only a task that needs a repair is rewritten; the planner then receives the repaired text
(:mod:`twostep.pddl.writer`), every other task its files as they are. (The other LLM+P
quirk, actions named like predicates, needs no repair: names of actions and predicates
live apart.)
"""

from __future__ import annotations

from twostep.pddl.errors import PDDLError
from twostep.pddl.sexp import SExp, TypeSpec, define_body, section, typed_list, typed_names


def _undeclared_constants(domain_body: list[SExp]) -> set[str]:
    """Names that domain actions and rules use as objects without declaring them."""
    predicates = {
        p[0] for p in (section(domain_body, ":predicates") or [])[1:] if isinstance(p, list) and p
    }
    constants = {n for n, _ in typed_names((section(domain_body, ":constants") or [":c"])[1:])}
    found: set[str] = set()

    def visit(expr: SExp) -> None:
        if not isinstance(expr, list) or not expr:
            return
        head = expr[0]
        if isinstance(head, str) and (head in predicates or head == "="):
            for term in expr[1:]:
                if isinstance(term, str) and not term.startswith("?") and term not in constants:
                    found.add(term)
        for sub in expr[1:]:
            visit(sub)

    for item in domain_body:
        if isinstance(item, list) and item and item[0] == ":action":
            for key, value in zip(item[2::2], item[3::2], strict=False):
                if key in (":precondition", ":effect"):
                    visit(value)
        elif isinstance(item, list) and item[:1] == [":derived"] and len(item) == 3:
            visit(item[2])
    return found


def _argument_types(domain_body: list[SExp], names: set[str]) -> dict[str, str]:
    """The declared type of the predicate argument each of ``names`` first fills."""
    declarations = {
        str(p[0]): [t for _, t in typed_names(p[1:])]
        for p in (section(domain_body, ":predicates") or [])[1:]
        if isinstance(p, list) and p
    }
    found: dict[str, str] = {}

    def visit(expr: SExp) -> None:
        if not isinstance(expr, list) or not expr:
            return
        head = expr[0]
        types = declarations.get(head) if isinstance(head, str) else None
        if types is not None:
            for position, term in enumerate(expr[1:]):
                if term in names and term not in found:
                    found[str(term)] = types[position] if position < len(types) else "object"
        for sub in expr[1:]:
            visit(sub)

    for item in domain_body:
        if isinstance(item, list) and item[:1] in ([":action"], [":derived"]):
            visit(item)
    return {name: found.get(name, "object") for name in names}


def _declare_constants(
    domain_body: list[SExp], problem_body: list[SExp]
) -> tuple[list[SExp], list[SExp]] | None:
    """The bodies with undeclared objects moved into the domain's constants (None: none)."""
    missing = _undeclared_constants(domain_body)
    if not missing:
        return None
    objects_section = section(problem_body, ":objects") or [":objects"]
    declared = dict(typed_names(objects_section[1:]))
    # a name nobody declares (AlfWorld's KnifeType in a task without knives) is typed as
    # its predicate declares the argument: no fact names it, so it changes nothing
    for name, type_name in _argument_types(domain_body, missing - declared.keys()).items():
        declared[name] = type_name
    typed = section(domain_body, ":types") is not None
    constants_section = section(domain_body, ":constants")
    new_constants: list[SExp] = [":constants"]
    if constants_section is not None:
        new_constants += constants_section[1:]
    for name in sorted(missing):
        new_constants += [name, "-", declared[name]] if typed else [name]
    rebuilt: list[SExp] = []
    inserted = False
    for item in domain_body:
        if item is constants_section:
            continue
        if not inserted and isinstance(item, list) and item and item[0] == ":predicates":
            rebuilt.append(new_constants)
            inserted = True
        rebuilt.append(item)
    if not inserted:
        rebuilt.insert(2, new_constants)
    kept: list[SExp] = [":objects"]
    for name, type_name in typed_names(objects_section[1:]):
        if name not in missing:
            kept += [name, "-", type_name]
    problem_rebuilt = [kept if item is objects_section else item for item in problem_body]
    return rebuilt, problem_rebuilt


def _type_text(spec: TypeSpec) -> str:
    return spec if isinstance(spec, str) else "(either " + " ".join(spec) + ")"


def _drop_duplicate_objects(
    domain_body: list[SExp], problem_body: list[SExp], problem_source: str | None
) -> list[SExp] | None:
    """The problem body without the objects the domain declares as constants (None: there
    are none); a problem object typed otherwise than its constant is a :class:`PDDLError`."""
    constants_section = section(domain_body, ":constants")
    objects_section = section(problem_body, ":objects")
    if constants_section is None or objects_section is None:
        return None
    constants = dict(typed_list(constants_section[1:]))
    objects = typed_list(objects_section[1:])
    duplicates = [(name, spec) for name, spec in objects if name in constants]
    if not duplicates:
        return None
    for name, spec in duplicates:
        if spec not in (constants[name], "object"):
            raise PDDLError(
                f"object '{name}' is declared here of type '{_type_text(spec)}', but the "
                f"domain declares it as a constant of type '{_type_text(constants[name])}'",
                problem_source,
            )
    kept: list[SExp] = [":objects"]
    for name, spec in objects:
        if name not in constants:
            kept += [name, "-", spec if isinstance(spec, str) else ["either", *spec]]
    return [kept if item is objects_section else item for item in problem_body]


def _without_commas(expr: SExp) -> tuple[SExp, bool]:
    """``expr`` with commas dropped from its tokens, and whether there were any."""
    if isinstance(expr, str):
        token = expr.rstrip(",")
        return token, token != expr
    out: list[SExp] = []
    changed = False
    for part in expr:
        cleaned, was = _without_commas(part)
        changed |= was
        if cleaned != "":
            out.append(cleaned)
    return out, changed


def repair_task(
    domain_text: str, problem_text: str, domain_source: str | None, problem_source: str | None
) -> tuple[list[SExp], list[SExp], bool]:
    """The domain's and the problem's ``define`` bodies, repaired where they need it (see
    the module docstring), and whether anything was repaired."""
    domain_body = define_body(domain_text, "domain", domain_source)
    problem_body = define_body(problem_text, "problem", problem_source)
    cleaned, commas = _without_commas(domain_body)
    assert isinstance(cleaned, list)
    domain_body = cleaned
    deduplicated = _drop_duplicate_objects(domain_body, problem_body, problem_source)
    if deduplicated is not None:
        problem_body = deduplicated
    moved = _declare_constants(domain_body, problem_body)
    if moved is not None:
        domain_body, problem_body = moved
    return domain_body, problem_body, commas or deduplicated is not None or moved is not None
