"""The experiments the benches run and the tests check, as code both import (not installed
with twostep; ``bench/bench_*.py`` are their command lines: arguments, timing, printing).
Nothing here imports a bench script (``tests/test_tests_in_order.py``).

* :mod:`evaluation.methods`: every method on a task of a data root, re-validated; the rows
  a run keeps and reuses; :mod:`evaluation.method_tables`: their tables, figure, results
  pages and the README's headline;
* :mod:`evaluation.heldout`: the LLM+P files as a held-out data root, re-validated and
  cross-checked against our domains;
* :mod:`evaluation.portfolio_members`: smaller portfolios replayed from a portfolio's rows;
* :mod:`evaluation.conformance`: real PDDL read, planned and validated as Fast Downward
  does; :mod:`evaluation.load_time`: the load-time part of its results page;
* :mod:`evaluation.deal_checks`: plan-deal within a time limit and its two verdicts;
* :mod:`evaluation.tracks`: the tracks problems the parallel-execution scorer is measured
  and tested on (``tests/examples.py`` takes its domain from here);
* :mod:`evaluation.prefect_server`: the Prefect server's start-up, timed;
* :mod:`evaluation.pages`: the results page of each other bench's rows.
"""
