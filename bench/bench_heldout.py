"""A held-out data root from the LLM+P benchmark files (the paper's own task files), for
``bench/bench_methods.py``.

The TwoStep paper's symbolic tasks are the LLM+P benchmark's (github.com/Cranial-XIX/llm-pddl,
``domains/<domain>/p01.pddl`` ... ``p20.pddl``); this repository ships none of them. Given a
checkout of that repository, this script lays them out as a data root (``<out>/<domain>/``
with ``domain.pddl`` and the problems, copied as they are) so that the methods bench runs on
them exactly as on ``data/``:

    git clone https://github.com/Cranial-XIX/llm-pddl /tmp/llm-pddl
    python bench/bench_heldout.py --llmp /tmp/llm-pddl --out /tmp/llmp
    python bench/bench_methods.py --data /tmp/llmp --agents 2 3 4 --methods plan-deal \\
        --domains barman blocksworld grippers termes tyreworld storage floortile \\
        --agent-predicates bench/heldout_agents.yaml --out outputs/bench/methods_heldout.json

LLM+P's blocksworld folder has problems but no domain file: its problems are untyped and name
the domain ``blocksworld-4ops`` (the four operators of ``data/blocksworld``, with the same
predicates), so the script writes ``data/blocksworld/domain.pddl`` without its types and under
that name. Storage and floortile are not among our domains: their agent predicates are in
``bench/heldout_agents.yaml``.
"""

from __future__ import annotations

import argparse
import re
import shutil
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
DOMAINS = ("barman", "blocksworld", "grippers", "termes", "tyreworld", "storage", "floortile")
PROBLEM = re.compile(r"p\d\d\.pddl")
DOMAIN_NAME = re.compile(r"\(\s*:domain\s+([^\s()]+)\s*\)", re.IGNORECASE)


def untyped_domain(text: str, name: str) -> str:
    """A STRIPS domain file without its types, named ``name``: every ``- type`` after a
    variable, the ``(:types ...)`` section and the ``:typing`` requirement removed."""
    text = re.sub(r"\(:types[^)]*\)\s*", "", text, flags=re.IGNORECASE)
    text = re.sub(r"(\?[\w-]+)\s+-\s+[\w-]+", r"\1", text)
    text = re.sub(r"\s*:typing", "", text, flags=re.IGNORECASE)
    return re.sub(r"\(\s*domain\s+[^\s()]+\s*\)", f"(domain {name})", text, count=1)


def problem_domain(path: Path) -> str:
    """The domain name a problem file asks for."""
    found = DOMAIN_NAME.search(path.read_text())
    if found is None:
        raise ValueError(f"{path}: no (:domain ...)")
    return found.group(1)


def prepare(llmp: Path, out: Path, domains: tuple[str, ...] = DOMAINS) -> dict[str, int]:
    """Lay out ``domains`` of the LLM+P checkout ``llmp`` as a data root at ``out``; return
    how many problems each domain has."""
    source = llmp / "domains" if (llmp / "domains").is_dir() else llmp
    counts: dict[str, int] = {}
    for domain in domains:
        folder = source / domain
        problems = sorted(p for p in folder.glob("p*.pddl") if PROBLEM.fullmatch(p.name))
        if not problems:
            raise FileNotFoundError(f"{folder}: no p01.pddl ... p20.pddl")
        target = out / domain
        target.mkdir(parents=True, exist_ok=True)
        for problem in problems:
            shutil.copyfile(problem, target / problem.name)
        if (folder / "domain.pddl").is_file():
            shutil.copyfile(folder / "domain.pddl", target / "domain.pddl")
        elif domain == "blocksworld":
            ours = (REPO / "data" / "blocksworld" / "domain.pddl").read_text()
            name = problem_domain(problems[0])
            (target / "domain.pddl").write_text(untyped_domain(ours, name))
        else:
            raise FileNotFoundError(f"{folder}: no domain.pddl")
        counts[domain] = len(problems)
    return counts


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--llmp", type=Path, required=True, help="a checkout of llm-pddl")
    parser.add_argument("--out", type=Path, required=True, help="the data root to write")
    parser.add_argument("--domains", nargs="*", default=list(DOMAINS))
    args = parser.parse_args(argv)
    try:
        counts = prepare(args.llmp, args.out, tuple(args.domains))
    except (FileNotFoundError, ValueError) as error:
        print(f"bench_heldout: {error}", file=sys.stderr)
        return 2
    for domain, n in counts.items():
        print(f"{args.out / domain}: {n} problems")
    return 0


if __name__ == "__main__":
    sys.exit(main())
