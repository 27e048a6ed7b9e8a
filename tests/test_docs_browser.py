"""The documentation site in a real browser: ``mkdocs build --strict`` into a temporary
folder, served on 127.0.0.1, then headless Chromium on the home page, a how-to guide, the
tutorial, the config reference and a results page; each must render its text, and every
image of a page (the tutorial's UI screenshots, the results page's figures) must have
loaded.

Slow (a build and a browser: under a minute); ``make ui-check`` runs it. Screenshots of
each page go to ``TWOSTEP_SITE_SCREENSHOTS=<folder>`` when it is set (else the test's
temporary folder). Skips, with a message, where Chromium is not installed
(``apt-get install -y chromium``).
"""

from __future__ import annotations

import functools
import os
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

from flows.servers import free_port
from tests.browser import Browser, poll
from tests.support.skips import skip_without_chromium

REPO = Path(__file__).resolve().parent.parent

PAGES = {  # page -> texts it must show
    "index.html": ["Multi-agent task planning", "Tutorial", "How-to guides", "Reference",
                   "Explanations", "Results"],
    "how-to/own-llm.html": ["Your own LLM", "llm.mode", "One cache, one retry loop"],
    "tutorial/index.html": ["Tutorial", "As a library", "A sweep", "Compare the runs in MLflow"],
    "reference/config.html": ["Configuration keys", "orchestration.task_runner", "Config groups",
                              "hydra/launcher"],
    "results/methods.html": ["All methods on the 100 tasks", "The runs", "Macro exec/SA",
                             "portfolio-lite"],
    "results/replay.html": ["The paper's own model answers, replayed", "Table I from the "
                            "replayed answers", "official TwoStep (its logs)", "check_run"],
    "results/deal-beyond.html": ["plan-deal beyond the benchmark", "deal_generated.json",
                                 "The eight ways to deal"],
}  # fmt: skip
IMAGES = """Array.from(document.querySelectorAll('article img')).map(
  i => ({src: i.getAttribute('src'), complete: i.complete, width: i.naturalWidth}))"""


class _Quiet(SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: object) -> None:
        pass


@contextmanager
def served(folder: Path) -> Iterator[str]:
    """The folder over HTTP on 127.0.0.1 (a thread of this process, stopped on exit)."""
    port = free_port()
    handler = functools.partial(_Quiet, directory=str(folder))
    server = ThreadingHTTPServer(("127.0.0.1", port), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        server.shutdown()
        server.server_close()
        thread.join(10)


@pytest.mark.slow
def test_the_built_site_renders_its_pages_and_figures(tmp_path: Path) -> None:
    binary = skip_without_chromium()
    site = tmp_path / "site"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    mkdocs = Path(sys.executable).with_name("mkdocs")
    built = subprocess.run([str(mkdocs), "build", "--strict", "--quiet", "-d", str(site)],
                           cwd=REPO, env=env, capture_output=True, text=True, timeout=300)  # fmt: skip
    assert built.returncode == 0, built.stderr[-3000:]
    shots = Path(os.environ.get("TWOSTEP_SITE_SCREENSHOTS") or tmp_path / "shots")
    shots.mkdir(parents=True, exist_ok=True)
    browser = Browser(binary, tmp_path / "chromium", size=(1400, 1000))
    try:
        with served(site) as base:
            for page, texts in PAGES.items():
                browser.open(f"{base}/{page}")
                browser.wait_for(texts, timeout_s=60)

                def loaded() -> list[dict[str, object]] | None:
                    images = browser.run(IMAGES) or []
                    return images if all(i["complete"] for i in images) else None

                images = poll(loaded, lambda: "images still loading", 30, 0.5)
                broken = [i["src"] for i in images if not i["width"]]
                assert not broken, f"{page}: images that did not load: {broken}"
                if page.startswith("results/"):  # its figure: an SVG, or the replay's PNG
                    assert any(str(i["src"]).endswith((".svg", ".png")) for i in images), images
                if images:  # the first figure in view
                    browser.run(
                        "document.querySelector('article img').scrollIntoView({block: 'center'})"
                    )
                    time.sleep(0.5)
                name = page.replace("/", "-").removesuffix(".html")
                browser.screenshot(shots / f"site-{name}.png")
            # a link of the nav leads somewhere: the reference's API index lists the packages
            browser.open(f"{base}/reference/api/index.html")
            browser.wait_for(["Library API", "twostep.dealing", "flows.tracking"], timeout_s=60)
    finally:
        browser.close()
