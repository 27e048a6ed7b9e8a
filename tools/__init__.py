"""Tools of the repository itself (not installed with twostep): the documentation site's
generated reference pages (:mod:`tools.reference`) and the MkDocs hook that adds them to
the site (``tools/mkdocs_hooks.py``)."""
