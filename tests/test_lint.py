"""The PDDL lint before Fast Downward (issue 39, finding 11): a type-name typo is reported
as such, with file and line, and never stored as "search proved unsolvable".

Before: an action parameter of an undeclared type (``?t - lorry``) and a goal atom with an
object of the wrong type were both ``FAILED (unsolvable: search proved unsolvable)``,
stored in the job store; a predicate of an undeclared type, a type cycle and a mistyped
initial fact were accepted silently (Fast Downward accepts all of these). A domain file
holding a problem was read as a domain (``unknown predicate 'arm-empty' in :init``).

Fast Downward's translator is the reference reader, so the lint must reject nothing it
reads as meant: it runs over every domain and problem of the IPC sample (when
``../shared/ipc-sample`` is there), the benchmark data, the test fixtures and AlfWorld's
``alfred.pddl`` (with the ``embodied`` extra) with no finding.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from checkers.trace_check import alfworld_layouts_folder
from tests.conftest import DATA
from tests.support.skips import IPC_SAMPLE, needs_ipc_sample
from twostep.pddl import PDDLError
from twostep.pddl.lifted import read_domain, read_problem
from twostep.pddl.lint import check_kinds, lint_domain, lint_problem
from twostep.pddl.reader import parse_problem, read_pddl_file
from twostep.pddl.repairs import repair_task

REPO = Path(__file__).resolve().parent.parent
FIXTURES = Path(__file__).resolve().parent / "fixtures"
BIN = Path(sys.executable).parent

DELIV = """(define (domain deliv)
  (:requirements :strips :typing)
  (:types truck place pkg)
  (:predicates (at ?t - truck ?p - place) (pat ?k - pkg ?p - place)
               (in ?k - pkg ?t - truck) (road ?a ?b - place))
  (:action drive :parameters (?t - truck ?a ?b - place)
    :precondition (and (at ?t ?a) (road ?a ?b))
    :effect (and (at ?t ?b) (not (at ?t ?a))))
  (:action load :parameters (?k - pkg ?t - truck ?p - place)
    :precondition (and (at ?t ?p) (pat ?k ?p))
    :effect (and (in ?k ?t) (not (pat ?k ?p))))
  (:action unload :parameters (?k - pkg ?t - truck ?p - place)
    :precondition (and (at ?t ?p) (in ?k ?t))
    :effect (and (pat ?k ?p) (not (in ?k ?t)))))
"""
D1 = """(define (problem d1) (:domain deliv)
  (:objects t1 t2 - truck l1 l2 l3 - place k1 k2 - pkg)
  (:init (at t1 l1) (at t2 l3) (pat k1 l1) (pat k2 l3)
         (road l1 l2) (road l2 l1) (road l2 l3) (road l3 l2))
  (:goal (and (pat k1 l3) (pat k2 l1))))
"""

# (what changes, in the domain or the problem; the line it is on; words of the message)
CASES = [
    ("(:action drive :parameters (?t - truck", "(:action drive :parameters (?t - lorry",
     "domain", 6, "action drive: type 'lorry' is not declared (types: pkg, place, truck)"),
    ("(in ?k - pkg ?t - truck)", "(in ?k - pkg ?t - lorry)",
     "domain", 5, "predicate in: type 'lorry' is not declared"),
    ("(:types truck place pkg)", "(:types truck - pkg pkg - truck place)",
     "domain", 3, "the types' parents form a cycle (truck - pkg - truck)"),
    ("(and (at ?t ?a) (road ?a ?b))", "(and (at ?t ?a) (road ?a))",
     "domain", 7, "action drive: predicate 'road' takes 2 argument(s), 1 given: (road ?a)"),
    ("(not (at ?t ?a))))", "(not (at ?t ?target))))",
     "domain", 8, "action drive: variable ?target is not declared"),
    ("(?t - truck ?a ?b - place)", "(?t - truck ?a ?a - place)",
     "domain", 6, "action drive: parameter ?a is declared twice"),
    ("(pat k2 l1))))", "(pat k2 t1))))",
     "problem", 5, ":goal: (pat k2 t1): 't1' is of type 'truck', but argument 2 of 'pat' is of type 'place'"),
    ("(at t2 l3)", "(at t2 k1)",
     "problem", 3, ":init: (at t2 k1): 'k1' is of type 'pkg', but argument 2 of 'at' is of type 'place'"),
]  # fmt: skip


@pytest.mark.parametrize(("old", "new", "where", "line", "words"), CASES)
def test_the_lint_names_the_mistake_with_file_and_line(
    old: str, new: str, where: str, line: int, words: str
) -> None:
    domain, problem = DELIV, D1
    if where == "domain":
        assert old in domain
        domain = domain.replace(old, new, 1)
    else:
        assert old in problem
        problem = problem.replace(old, new, 1)
    with pytest.raises(PDDLError) as caught:
        parse_problem(domain, problem, "domain.pddl", "p01.pddl")
    assert caught.value.source == f"{where}.pddl".replace("problem", "p01")
    assert caught.value.line == line, str(caught.value)
    assert words in caught.value.message


def test_the_files_as_written_pass() -> None:
    problem = parse_problem(DELIV, D1, "domain.pddl", "p01.pddl")
    assert len(problem.objects) == 7


def test_swapped_files_are_named() -> None:
    with pytest.raises(PDDLError, match="defines a problem, not a domain") as caught:
        parse_problem(D1, DELIV, "domain.pddl", "p01.pddl")
    assert (caught.value.source, caught.value.line) == ("domain.pddl", 1)


def test_a_type_typo_is_an_input_error_not_unsolvable(tmp_path: Path) -> None:
    folder = tmp_path / "data" / "x"
    folder.mkdir(parents=True)
    (folder / "domain.pddl").write_text(DELIV.replace("(?t - truck ?a ?b", "(?t - lorry ?a ?b"))
    (folder / "p01.pddl").write_text(D1)
    out = tmp_path / "out"
    done = subprocess.run(
        [str(BIN / "twostep"), f"data.root={tmp_path / 'data'}", "domain.name=x",
         "domain.agent_predicates=[at,in]", "task=1", "method=twostep", "agents=2",
         f"output.root={out}", "mlflow.enabled=false", "orchestration.prefect=false"],
        capture_output=True, text=True, timeout=240,
    )  # fmt: skip
    assert done.returncode == 2, done.stdout + done.stderr
    errors = [line for line in done.stderr.splitlines() if line.strip()]
    assert errors == [
        f"error: {folder / 'domain.pddl'}:6: action drive: type 'lorry' is not declared "
        "(types: pkg, place, truck)"
    ]
    assert "unsolvable" not in done.stdout + done.stderr
    assert not list((out / "jobs").glob("*/result.json"))


# ----------------------------------------------------------------- no false positives


def corpus() -> list[tuple[Path, Path]]:
    """Every (domain, problem) pair of the IPC sample, the data and the fixtures."""
    domains = sorted(IPC_SAMPLE.glob("*/domain.pddl")) + sorted(DATA.glob("**/domain.pddl"))
    domains += sorted(FIXTURES.glob("**/domain.pddl"))
    pairs = [(d, p) for d in domains for p in sorted(d.parent.glob("*.pddl")) if p != d]
    layouts = alfworld_layouts_folder()  # None without the embodied extra
    if layouts is not None:
        wheel = Path(str(layouts)).parent.parent / "data" / "alfred.pddl"
        pairs.append((wheel, FIXTURES / "alfred_scene" / "alfred" / "p01.pddl"))
    return pairs


def test_the_lint_finds_nothing_in_valid_files() -> None:
    pairs = corpus()
    assert len(pairs) >= 150  # the data and the fixtures at least
    findings = []
    for domain_path, problem_path in pairs:
        domain_text, problem_text = read_pddl_file(domain_path), read_pddl_file(problem_path)
        sources = (str(domain_path), str(problem_path))
        domain_body, problem_body, _ = repair_task(domain_text.removeprefix("\ufeff"),
                                                   problem_text.removeprefix("\ufeff"), *sources)  # fmt: skip
        domain = read_domain(domain_body, domain_text, sources[0])
        parts = read_problem(problem_body, domain, problem_text, sources[1])
        try:
            check_kinds(domain_body, problem_body, sources, (domain_text, problem_text))
            lint_domain(domain, domain_text, sources[0])
            lint_problem(domain, parts, problem_body, problem_text, sources[1])
        except PDDLError as error:
            findings.append(str(error))
    assert findings == []


@needs_ipc_sample
def test_the_ipc_sample_is_in_the_corpus() -> None:
    assert sum(1 for d, _ in corpus() if IPC_SAMPLE in d.parents) >= 30
