"""Real answers replayed: the importer (official log format), the bundle, the client's
bundle mode, TwoStep on replayed answers, the translation check and the replay grid.

The logs are written by the tests in the official format (tests/replay_logs.py) about
twostep's own data/ tasks; every expected value is derived by hand from those logs and
tasks (line numbers counted in the text the test writes, plan costs from the PDDL).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from flows.replay_grid import replay_jobs
from tests.replay_logs import SEPARATOR, block
from twostep.cli.data import main as data_main
from twostep.decomposers.llm import LLMDecomposer, generate_subgoal, translate_subgoal
from twostep.llm import LLMBundleMiss, LLMClient, LLMSettings
from twostep.methods import MethodRequest, check_run, run_twostep
from twostep.planner import PlannerSettings
from twostep.replay import BUNDLE_FILE, BundleMiss, load_bundle
from twostep.replay.check import DIFFERS, MATCH, UNTRANSLATED, check_entry, summarise
from twostep.replay.importer import AnswerImportError, import_logs
from twostep.tasks.benchmark import load_task

BLOCKS = ["arm-empty", "holding"]
# data/blocksworld/p01: b1 on b2, b3 on b1, b2 on the table (goal: b1 on b2, b2 on b3);
# p02: see test_check_against_the_logged_costs.
P01_N2 = block("blocksworld", 1, ["b3 is clear and on the table."], helper_costs=[2.0])
P01_N3 = block(
    "blocksworld",
    1,
    [
        "b3 is clear and on the table.",
        "b1 is clear and all hands are empty. \n agent3 subgoal: b2 is clear.",
    ],
    helper_costs=[2.0, 0.0],
    run=1001,
)


def write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.fixture
def two_runs(tmp_path: Path, data_root: Path) -> Path:
    """A bundle of two logs: N = 2 (p01, and p02 whose run crashed after the answers) and
    N = 3 (p01)."""
    n2 = P01_N2 + block(
        "blocksworld", 2, ["b1 is on the table and all hands are empty."], crash_after_answers=True
    )
    one = write(tmp_path, "run_2_agent.txt", n2)
    two = write(tmp_path, "run_3_agent.txt", P01_N3)
    out = tmp_path / "bundle"
    import_logs([one, two], "gpt-4o", out, tasks=data_root)
    return out


# ------------------------------------------------------------------ importing


def test_import_reads_answers_numbers_and_provenance(two_runs: Path) -> None:
    bundle = load_bundle(two_runs)
    assert [(r.id, r.file, r.label, r.model) for r in bundle.runs] == [
        ("run_2_agent", "run_2_agent.txt", "1000", "gpt-4o"),
        ("run_3_agent", "run_3_agent.txt", "1001", "gpt-4o"),
    ]
    assert [e.key for e in bundle.entries] == [
        ("blocksworld", 1, 2),
        ("blocksworld", 2, 2),
        ("blocksworld", 1, 3),
    ]
    first, crashed, three = bundle.entries
    # the answer list is line 2 of the first block; a complete block of one helper is 12
    # lines (info, list, 3 of the helper, main, TASK, length, 3 of results, dashes): the
    # second block starts at line 13, its list on line 14
    assert (first.line, first.answers[0].text) == (2, "b3 is clear and on the table.")
    assert (crashed.line, crashed.answers[0].text) == (
        14,
        "b1 is on the table and all hands are empty.",
    )
    official = first.official
    assert (official.sa_cost, official.helper_costs, official.exec_length, official.valid) == (
        6.0, (2.0,), 5.0, True,
    )  # fmt: skip
    assert crashed.official.exec_length is None and crashed.official.sa_cost == 6.0
    assert [a.helper for a in three.answers] == [1, 2]
    assert three.official.helper_costs == (2.0, 0.0)
    assert bundle.task_digest("blocksworld", 1) is not None


def test_import_command_writes_the_bundle(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    log = write(tmp_path, "log.txt", P01_N2)
    out = tmp_path / "answers"
    code = data_main(
        [
            "import-answers",
            "--format",
            "twostep-official",
            str(log),
            "--out",
            str(out),
            "--model",
            "gpt-4o",
        ]
    )
    assert code == 0
    assert "log.txt run 1000 (gpt-4o): 1 task(s): blocksworld N=2: 1" in capsys.readouterr().out
    assert json.loads((out / BUNDLE_FILE).read_text())["entries"][0]["answers"][0]["line"] == 2


def test_reasoning_before_the_answers_and_blocks_without_answers(tmp_path: Path) -> None:
    """The 'choose N' logs print the model's reasoning before the list; a run that crashed
    before answering leaves a block without answers (counted, not imported)."""
    reasoning = ["To decide, look at the blocks.", "### Conclusion:", "Two agents are enough."]
    text = (
        "[info][singleagent][blocksworld] task 03 takes 0.1 sec, found a plan with cost 8.0\n"
        "Traceback (most recent call last):\nSyntaxError: invalid syntax\n"
        + SEPARATOR
        + "\n"
        + block("blocksworld", 1, ["b3 is clear."], before_answers=reasoning)
    )
    report = import_logs([write(tmp_path, "log.txt", text)], "m", tmp_path / "b")
    (entry,) = report.bundle.entries
    assert (entry.task, entry.line) == (1, 9)  # 4 lines, then the info line and 3 of reasoning
    assert report.without_answers == {"log.txt": 1}


def test_logged_translations_are_kept_replayed_and_compared(
    tmp_path: Path, data_root: Path
) -> None:
    text = block(
        "blocksworld",
        1,
        ["b3 is clear.", "b1 is clear."],
        translations=["(and (clear b3))", "(and (on-table b3))"],
    )
    (entry,) = import_logs([write(tmp_path, "log.txt", text)], "m", tmp_path / "b").bundle.entries
    assert entry.translations == ("(:goal (and (clear b3)) )", "(:goal (and (on-table b3)) )")
    task = load_task("blocksworld", 1, data_root)
    client = LLMClient(
        LLMSettings(model="m", mode="bundle", bundle=tmp_path / "b", translator="llm")
    )
    pddl, exchange = translate_subgoal(client, task, "b3 is clear", 0, helper=1, agents=3)
    assert pddl == "(and (clear b3))" and exchange["source"]["line"] == 2
    checks = check_entry(entry, task, BLOCKS, PlannerSettings(search_time_limit_s=10))
    # the rules read helper 1 as the model did, helper 2 otherwise
    assert [c.same_as_logged for c in checks] == [True, False]


@pytest.mark.parametrize(
    "text, where, what",
    [
        # a subgoal list cut short
        (
            P01_N2.replace("['b3 is clear and on the table.']", "['b3 is clear and on"),
            2,
            "malformed subgoal list",
        ),
        # a results line that does not parse
        (P01_N2.replace("[agents: 2]", "[agents: two]"), 11, "malformed line"),
        # answers before any task line
        ("['b3 is clear.']\n" + SEPARATOR + "\n", 1, "subgoals without a task"),
        # the log ends inside a block
        (
            P01_N2
            + "[info][singleagent][blocksworld] task 02 takes 0.1 sec, found a plan with cost 6.0\n",
            13,
            "truncated",
        ),
        # N-1 answers, but the results say another N
        (P01_N2.replace("[agents: 2]", "[agents: 3]"), 11, "does not match"),
    ],
)
def test_malformed_logs_are_one_line_naming_file_and_line(
    tmp_path: Path, text: str, where: int, what: str
) -> None:
    log = write(tmp_path, "bad.txt", text)
    out = tmp_path / "bundle"
    with pytest.raises(AnswerImportError) as error:
        import_logs([write(tmp_path, "good.txt", P01_N3), log], "gpt-4o", out)
    message = str(error.value)
    assert message.startswith(f"{log}:{where}: ") and what in message and "\n" not in message
    assert not out.exists()  # nothing half-written: not even the good log's bundle


def test_append_and_refusals(tmp_path: Path) -> None:
    first, second = write(tmp_path, "a.txt", P01_N2), write(tmp_path, "b.txt", P01_N3)
    out = tmp_path / "bundle"
    import_logs([first], "gpt-4o", out)
    before = (out / BUNDLE_FILE).read_text()
    with pytest.raises(AnswerImportError, match="exists: add to it with --append"):
        import_logs([second], "gpt-4o", out)
    with pytest.raises(AnswerImportError, match="already in the bundle"):
        import_logs([first], "gpt-4o", out, append=True)
    assert (out / BUNDLE_FILE).read_text() == before  # a refused import changes nothing
    bundle = import_logs([second], "o1-mini", out, append=True).bundle
    assert [r.model for r in bundle.runs] == ["gpt-4o", "o1-mini"]


# ------------------------------------------------------------------ the bundle


def test_the_seed_picks_the_run_and_misses_say_what_is_missing(tmp_path: Path) -> None:
    again = P01_N2.replace("b3 is clear and on the table.", "b3 is on the table.")
    out = tmp_path / "bundle"
    bundle = import_logs(
        [write(tmp_path, "r1.txt", P01_N2), write(tmp_path, "r2.txt", again)], "gpt-4o", out
    ).bundle
    assert (
        bundle.entry("blocksworld", 1, 2, "openai/gpt-4o", seed=1).answers[0].text
        == "b3 is on the table."
    )
    for args, message in [
        (("blocksworld", 1, 2, "o1-mini", 0), "no answers of model 'o1-mini'"),
        (("blocksworld", 1, 4, "gpt-4o", 0), "with 4 agents (N = 2)"),
        (("grippers", 1, 2, "gpt-4o", 0), "domains: blocksworld"),
        (("blocksworld", 1, 2, "gpt-4o", 2), "seed 2 asks for run 3"),
        (("blocksworld", 5, 2, "gpt-4o", 0), "no answers for blocksworld/p05 with 2 agents"),
    ]:
        with pytest.raises(BundleMiss, match=re.escape(message)):
            bundle.entry(*args)


def test_a_replay_on_other_task_files_is_refused(two_runs: Path, data_root: Path) -> None:
    bundle = load_bundle(two_runs)
    bundle.check_task_file("blocksworld", 1, data_root / "blocksworld" / "p01.pddl")
    with pytest.raises(BundleMiss, match="not the task file"):
        bundle.check_task_file("blocksworld", 1, data_root / "blocksworld" / "p02.pddl")


# ------------------------------------------------------------------ replaying


def replay(bundle: Path, translator: str = "rules") -> LLMClient:
    return LLMClient(LLMSettings(mode="bundle", bundle=bundle, translator=translator))


def test_the_client_answers_from_the_bundle_with_the_source(
    two_runs: Path, data_root: Path
) -> None:
    task = load_task("blocksworld", 1, data_root)
    english, exchange = generate_subgoal(
        replay(two_runs), task, 3, 2, ["b3 is clear and on the table"], 0
    )
    # helper 2's answer, up to the label of the subgoal the model went on to give agent3
    assert english == "b1 is clear and all hands are empty"
    assert exchange["source"] == {
        "kind": "replayed", "model": "gpt-4o", "run": "run_3_agent", "file": "run_3_agent.txt",
        "line": 2, "bundle": str(two_runs),
    }  # fmt: skip
    assert "agent2" in exchange["messages"][-2]["text"]  # our prompt is logged, as for a live call
    pddl, translated = translate_subgoal(replay(two_runs), task, english, 0, helper=2)
    assert pddl == "(and (arm-empty) (clear b1))" and translated["translator"] == "rules"
    with pytest.raises(LLMBundleMiss, match="logs no translations"):
        translate_subgoal(replay(two_runs, "llm"), task, english, 0, helper=2, agents=3)
    with pytest.raises(LLMBundleMiss, match="with 5 agents"):
        generate_subgoal(replay(two_runs), task, 5, 1, [], 0)


def test_twostep_on_replayed_answers(two_runs: Path, data_root: Path) -> None:
    """N = 3 on data/blocksworld/p01: helper 1 puts b3 down (2 steps), helper 2's
    subgoal (b1 clear, arm empty) then already holds: discarded; the schedule
    re-validates against the original task."""
    task = load_task("blocksworld", 1, data_root)
    request = MethodRequest(
        task, 3, PlannerSettings(search_time_limit_s=20), BLOCKS, LLMDecomposer(replay(two_runs))
    )
    run = run_twostep(request)
    assert run.success and run.extra["answer_source"] == "replayed, model gpt-4o, run_3_agent.txt:2"
    assert run.extra["translation"] == {"translator": "rules", "read": 2, "failed": 0}
    assert [(s["status"], s["reason"]) for s in run.subgoals] == [
        ("accepted", None),
        ("discarded", "already true in the helper's initial state"),
    ]
    assert run.plans["agent1"] == ["(unstack b3 b1)", "(putdown b3)"]
    check_run(task.problem, run, BLOCKS)


def test_a_sentence_the_rules_cannot_read_is_a_counted_discard(
    tmp_path: Path, data_root: Path
) -> None:
    log = write(tmp_path, "log.txt", block("blocksworld", 1, ["b3 floats above b2."]))
    import_logs([log], "gpt-4o", tmp_path / "b")
    task = load_task("blocksworld", 1, data_root)
    request = MethodRequest(
        task,
        2,
        PlannerSettings(search_time_limit_s=20),
        BLOCKS,
        LLMDecomposer(replay(tmp_path / "b")),
    )
    run = run_twostep(request)
    assert run.success and run.fallback is not None  # the SA plan, as for any unusable subgoal
    (subgoal,) = run.subgoals
    assert subgoal["status"] == "discarded"
    assert subgoal["reason"].startswith(
        "translation failed: no phrase of the domain reads 'b3 floats"
    )
    assert run.extra["translation"] == {"translator": "rules", "read": 0, "failed": 1}


# ------------------------------------------------------------------ the translation check


def test_check_against_the_logged_costs(tmp_path: Path, data_root: Path) -> None:
    """p01 at N = 3: b3 down costs 2 (unstack, putdown), then (b1 clear, arm empty) holds:
    0. Logged 2 and 0: both match. A logged 3 for the first would differ; an answer the
    rules cannot read is untranslated."""
    text = P01_N3 + block(
        "blocksworld", 1, ["b3 is clear and on the table.", "b2 levitates."], helper_costs=[3.0, 1.0],
        run=1002,
    )  # fmt: skip
    bundle = import_logs([write(tmp_path, "log.txt", text)], "m", tmp_path / "b").bundle
    task = load_task("blocksworld", 1, data_root)
    settings = PlannerSettings(alias="lama", search_time_limit_s=10)
    checks = [c for e in bundle.entries for c in check_entry(e, task, BLOCKS, settings)]
    assert [(c.status, c.cost, c.logged_cost, c.continued) for c in checks] == [
        (MATCH, 2.0, 2.0, False),
        (MATCH, 0.0, 0.0, True),  # its answer went on to agent3's subgoal
        (DIFFERS, 2.0, 3.0, False),
        (UNTRANSLATED, None, 1.0, False),
    ]
    (summary, _) = summarise(checks)
    assert summary == {
        "domain": "blocksworld", "subgoals": 4, "translated": 3, "compared": 3, "match": 2,
        "differs": 1, "differs_continued": 0, "differs_official_limit": 0,
        "differs_after_continued": 0, "differs_known": 0, "differs_other": 1,
        "translated_pct": 75.0, "match_pct": 66.7, "match_pct_comparable": 66.7,
        "with_logged_translation": 0, "same_as_logged": 0,
    }  # fmt: skip


def test_a_helper_after_an_answer_that_goes_on_starts_elsewhere(
    tmp_path: Path, data_root: Path
) -> None:
    """p01 (b3 on b1 on b2) at N = 3. Helper 1's answer goes on to helper 2's subgoal: the
    official code translated both (b3 and b1 on the table: 4 steps, logged) and helper 2's
    own goal then already held (logged "no solution found" at once). Read as twostep
    reads it, helper 1 puts b3 down (2 steps) and helper 2 still has b1 to move (2 steps):
    both differ, for the causes said beside them, and nothing is left unexplained."""
    text = block(
        "blocksworld", 1,
        ["b3 is clear and on the table. \n agent3 subgoal: b1 is on the table.",
         "b1 is on the table."],
        helper_costs=[4.0, None],
    )  # fmt: skip
    bundle = import_logs([write(tmp_path, "log.txt", text)], "m", tmp_path / "b").bundle
    task = load_task("blocksworld", 1, data_root)
    settings = PlannerSettings(alias="lama", search_time_limit_s=10)
    checks = [c for e in bundle.entries for c in check_entry(e, task, BLOCKS, settings)]
    assert [(c.status, c.cost, c.why) for c in checks] == [
        (DIFFERS, 2.0, "continued"),
        (DIFFERS, 2.0, "after_continued"),
    ]
    (summary, _) = summarise(checks)
    assert (summary["differs_known"], summary["differs_other"]) == (2, 0)
    assert summary["match_pct_comparable"] is None  # nothing left to compare


def test_an_empty_plan_is_what_the_official_code_logs_as_no_solution(
    tmp_path: Path, data_root: Path
) -> None:
    """The official code prints "no solution found" for a goal that already holds (its plan
    file has no step); one logged at the time limit is a real failure."""
    already = block("blocksworld", 1, ["b3 is clear."], helper_costs=[None])
    timed_out = already.replace(
        "task 01 takes 0.13 sec, no solution", "task 01 takes 99.8 sec, no solution"
    )
    bundle = import_logs(
        [write(tmp_path, "a.txt", already), write(tmp_path, "b.txt", timed_out)],
        "m",
        tmp_path / "b",
    ).bundle
    task = load_task("blocksworld", 1, data_root)
    settings = PlannerSettings(alias="lama", search_time_limit_s=100)
    checks = [c for e in bundle.entries for c in check_entry(e, task, BLOCKS, settings)]
    assert [(c.status, c.cost, c.logged_no_plan, c.why) for c in checks] == [
        (MATCH, 0.0, True, None),
        (DIFFERS, 0.0, True, "official_limit"),  # a known cause, said beside it
    ]


# ------------------------------------------------------------------ the grid


def test_the_grid_is_what_the_bundle_answers(two_runs: Path) -> None:
    bundle = load_bundle(two_runs)
    jobs = replay_jobs(bundle, "gpt-4o")
    shown = [" ".join(f"{k}={v}" for k, v in job.items()) for job in jobs]
    assert shown == [
        "domain=blocksworld task=1 method=sa agents=2 seed=0",
        "domain=blocksworld task=1 agents=2 method=ma seed=0",
        "domain=blocksworld task=1 agents=2 method=twostep decomposer=llm seed=0",
        "domain=blocksworld task=1 agents=2 method=plan-deal seed=0",
        "domain=blocksworld task=1 agents=3 method=ma seed=0",
        "domain=blocksworld task=1 agents=3 method=twostep decomposer=llm seed=0",
        "domain=blocksworld task=1 agents=3 method=plan-deal seed=0",
        "domain=blocksworld task=2 method=sa agents=2 seed=0",
        "domain=blocksworld task=2 agents=2 method=ma seed=0",
        "domain=blocksworld task=2 agents=2 method=twostep decomposer=llm seed=0",
        "domain=blocksworld task=2 agents=2 method=plan-deal seed=0",
    ]
    assert len(replay_jobs(bundle, "gpt-4o", ["twostep"], agents=[3])) == 1
    assert replay_jobs(bundle, "o1-mini") == []


# ------------------------------------------------------------------ job identity


def test_the_new_llm_keys_keep_stored_jobs_keys_and_the_bundle_is_an_input(tmp_path: Path) -> None:
    """llm.bundle and llm.translator at the values that compute what jobs computed before
    them leave the job key as it was; a bundle's content is one of the job's inputs."""
    from flows.identity import job_input_files, job_key

    before = {"domain": {"name": "blocksworld"}, "task": 1, "agents": 2, "seed": 0,
              "method": {"name": "twostep"}, "decomposer": {"name": "llm"},
              "llm": {"model": "openai/gpt-4o", "mode": "live"}}  # fmt: skip
    after = {**before, "llm": {**before["llm"], "bundle": None, "translator": "llm"}}
    assert job_key(after) == job_key(before)
    rules = {**before, "llm": {**before["llm"], "translator": "rules"}}
    assert job_key(rules) != job_key(before)
    replayed = {**before, "llm": {**before["llm"], "mode": "bundle", "bundle": str(tmp_path)}}
    files = job_input_files(replayed, tmp_path / "p01.pddl")
    assert files["llm_bundle"] == tmp_path / BUNDLE_FILE
