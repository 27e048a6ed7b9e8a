"""MkDocs hooks (``hooks:`` in mkdocs.yml): the reference pages generated from the code.

On every build, :mod:`tools.reference` writes the configuration keys, the console
commands' ``--help`` and one library API page per package; they are added to the site as
generated files (nothing is written into ``docs/``). The nav entry
``reference/api/index.md`` becomes a section holding the API index and every package's
page, so a package added or a module moved needs no edit of mkdocs.yml; the entry
``results/index.md`` is followed by every results page of :data:`tools.results.PAGES`.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

from tools import reference  # noqa: E402

API_INDEX = "reference/api/index.md"
RESULTS_INDEX = "results/index.md"
_pages: dict[str, str] = {}


def _api_section(nav: list[Any]) -> bool:
    """Replace the API index's nav entry with the API section (in place)."""
    for i, item in enumerate(nav):
        title, value = next(iter(item.items())) if isinstance(item, dict) else (None, item)
        if value == API_INDEX:
            entries: list[Any] = [API_INDEX]
            entries += [{f"{p}": f"reference/api/{p}.md"} for p in reference.packages()]
            nav[i] = {title or "Library API": entries}
            return True
        if isinstance(value, list) and _api_section(value):
            return True
    return False


def _results_pages(nav: list[Any]) -> bool:
    """After the results index's nav entry, one entry per results page (in place)."""
    from tools.results import PAGES

    for i, item in enumerate(nav):
        value = next(iter(item.values())) if isinstance(item, dict) else item
        if value == RESULTS_INDEX:
            nav[i + 1 : i + 1] = [{p.title: f"results/{p.slug}.md"} for p in PAGES]
            return True
        if isinstance(value, list) and _results_pages(value):
            return True
    return False


def on_config(config: Any) -> Any:
    if str(REPO) not in sys.path:  # MkDocs puts sys.path back after loading the hooks
        sys.path.insert(0, str(REPO))
    _pages.clear()
    _pages.update(reference.pages())
    if config.nav is not None:
        if not _api_section(config.nav):
            raise ValueError(f"mkdocs.yml: the nav has no entry {API_INDEX}")
        if not _results_pages(config.nav):
            raise ValueError(f"mkdocs.yml: the nav has no entry {RESULTS_INDEX}")
    return config


def on_files(files: Any, config: Any) -> Any:
    from mkdocs.structure.files import File

    for path, text in _pages.items():
        files.append(File.generated(config, path, content=text))
    return files
