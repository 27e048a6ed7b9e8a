"""The results pages of the benches' rows (``make results``: :mod:`tools.results` names each
page's renderer, ``evaluation.pages.<module>:page``), one module per bench, with the goals
and columns the bench prints its runs against."""
