"""Tools of the repository itself (not installed with twostep): the documentation site's
generated reference pages (:mod:`tools.reference`) and the MkDocs hook that adds them to
the site (``tools/mkdocs_hooks.py``); the benches' records (:mod:`tools.record`) and the
results pages and README blocks made from them (:mod:`tools.results`, ``make results``);
the bare-status-comparison finder (:mod:`tools.status_scan`)."""
