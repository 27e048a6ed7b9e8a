"""The experiments the benches run and the tests check, as code both import (not installed
with twostep; ``bench/bench_*.py`` are their command lines: arguments, timing, printing).

* :mod:`evaluation.methods`: every method on a task of a data root, re-validated; the rows
  a run keeps and reuses; :mod:`evaluation.method_tables`: their tables, figure, results
  pages and the README's headline;
* :mod:`evaluation.heldout`: the LLM+P files as a held-out data root, re-validated and
  cross-checked against our domains;
* :mod:`evaluation.portfolio_members`: smaller portfolios replayed from a portfolio's rows.
"""
