"""Overhead of the LLM client when the answer is cached (goal: median under 5 ms).

Run: .venv/bin/python bench/bench_llm_client.py [--calls 200] [--json docs/bench/llm_client.json]

Measures ``LLMClient.complete`` on a prompt of the generator's size for: a cache hit in
live mode, a replay hit, a scripted answer, and (for scale) an uncached call answered by
litellm's ``mock_response``, which goes through litellm without any network. ``--json
FILE`` also writes every call's time as a bench record (:mod:`tools.record`), which
``make results`` renders (:func:`evaluation.pages.llm_client.page`).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from evaluation.pages.llm_client import GOAL_MS
from tools import record
from twostep.llm.client import LLMClient, LLMSettings
from twostep.llm.prompts import template


def measure(call: Callable[[int], object], calls: int) -> list[float]:
    times = []
    for i in range(calls):
        start = time.perf_counter()
        call(i)
        times.append((time.perf_counter() - start) * 1000)
    return sorted(times)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=200)
    parser.add_argument("--json", type=Path, help="also write the rows here (a bench record)")
    args = parser.parse_args()
    run = record.started()
    calls = args.calls
    prompt = [
        {"role": "system", "content": template("generator_system").template},
        {"role": "user", "content": template("generator_example").template * 2},
    ]
    size = sum(len(m["content"]) for m in prompt)
    print(f"$ {sys.executable} {' '.join(sys.argv)}")
    print(f"{calls} calls, prompt of {size} characters\n")
    with tempfile.TemporaryDirectory() as tmp:
        os.environ.setdefault("TWOSTEP_BENCH_KEY", "not-a-key")  # mock_response needs none
        extra = {"mock_response": "(:goal (and (on-table b1) (arm-empty)))"}
        live = LLMClient(
            LLMSettings(cache_dir=Path(tmp), extra=extra, api_key_env="TWOSTEP_BENCH_KEY")
        )
        start = time.perf_counter()
        live.complete(prompt, seed=0)  # imports litellm and fills the cache
        first = (time.perf_counter() - start) * 1000
        replay = LLMClient(LLMSettings(cache_dir=Path(tmp), extra=extra, mode="replay"))
        scripted = LLMClient(LLMSettings(mode="scripted"), answers=["none"] * calls)
        uncached = LLMClient(replace(live.settings, use_cache=False))
        rows = [
            ("cache hit (mode=live)", measure(lambda i: live.complete(prompt, 0), calls)),
            ("cache hit (mode=replay)", measure(lambda i: replay.complete(prompt, 0), calls)),
            ("scripted answer", measure(lambda i: scripted.complete(prompt, 0), calls)),
            (
                "litellm mock_response, no cache",
                measure(lambda i: uncached.complete(prompt, i), calls),
            ),
        ]
    print(f"first call (litellm import + mock + cache write): {first:.0f} ms\n")
    print(f"| {'call':<32} | median ms | p95 ms |")
    print(f"|{'-' * 34}|-----------|--------|")
    for name, times in rows:
        p95 = times[min(len(times) - 1, int(0.95 * len(times)))]
        print(f"| {name:<32} | {statistics.median(times):9.3f} | {p95:6.3f} |")
    hit = statistics.median(rows[0][1])
    verdict = "meets" if hit < GOAL_MS else "MISSES"
    print(
        f"\ncache-hit median {hit:.3f} ms {verdict} the 5 ms goal; "
        f"{statistics.median(rows[3][1]) / hit:.0f}x faster than a mocked litellm call"
    )
    if args.json:
        record.write(args.json, run, [{"call": n, "ms": t} for n, t in rows], calls=calls,
                     prompt_chars=size, first_call_ms=first, goal_ms=GOAL_MS)  # fmt: skip
    return 0 if hit < GOAL_MS else 1


if __name__ == "__main__":
    raise SystemExit(main())
