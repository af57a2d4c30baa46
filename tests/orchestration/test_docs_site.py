"""The documentation site: its sources cover the package, and the built site renders.

The first tests read the sources only (default run, no extra needed). The ``docs``-marked
tests open the site built by ``python docs/build.py`` in headless Chromium (Debian's
``chromium`` and ``chromium-driver``, the ``docs`` extra's selenium); they are opt-in
(``pytest -m docs tests/orchestration/test_docs_site.py``) and run by ``.ci/run`` after the build.
"""

from __future__ import annotations

import fnmatch
import functools
import http.server
import os
import re
import shutil
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
from conftest import ROOT

DOCS = ROOT / "docs"
SITE = DOCS / "_build" / "html"
#: The page of the API reference the browser test opens (a module with maths and tables).
API_PAGE = "api/generated/taopt.models.routing.html"


def _toctree_entries() -> str:
    return (DOCS / "index.md").read_text(encoding="utf-8")


def test_every_schema_is_on_the_schemas_page() -> None:
    """The generated docs/schemas.md (docs/generated.py, written at every build) includes every
    JSON Schema shipped in taopt/schemas/."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("generated", DOCS / "generated.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    page = module.generated_pages()["schemas.md"]
    schemas = sorted((ROOT / "taopt" / "schemas").glob("*.schema.json"))
    assert schemas
    missing = [s.name for s in schemas if f"../taopt/schemas/{s.name}" not in page]
    assert not missing, f"docs/schemas.md lacks {missing}"


def test_notebooks_are_linked_not_copied() -> None:
    """docs/notebooks is a symbolic link to notebooks/, so the site renders the real files."""
    link = DOCS / "notebooks"
    assert link.is_symlink(), "docs/notebooks must be a symbolic link to ../notebooks"
    assert link.resolve() == (ROOT / "notebooks").resolve()
    assert "notebooks/*" in _toctree_entries()


def test_every_page_is_in_a_toctree() -> None:
    """Every Markdown page of docs/ (reports, formats, benchmarks) is reachable from the index."""
    index = _toctree_entries()
    pages = [
        p.relative_to(DOCS).with_suffix("").as_posix()
        for p in DOCS.rglob("*.md")
        if "_build" not in p.parts
        and "_includes" not in p.parts  # generated fragments, included into pages
        and p.parent.name not in ("api", "notebooks")
        and p.name != "index.md"
    ]
    assert pages
    globs = re.findall(r"^([\w/-]+\*)$", index, re.MULTILINE)  # a :glob: toctree's patterns
    missing = [
        p
        for p in pages
        if not re.search(rf"^{re.escape(p)}$", index, re.MULTILINE)
        and not any(fnmatch.fnmatch(p, pattern) for pattern in globs)
    ]
    assert not missing, f"pages in no toctree of docs/index.md: {missing}"


def _chapter(text: str) -> tuple[int, bool]:
    """(chapter, is a certification family) named in a title: "(chapter 3)", "(§6.2 ...)"."""
    found = re.search(r"chapter (\d+)|§(\d+)", text)
    assert found, f"no chapter named in {text!r}"
    return int(found.group(1) or found.group(2)), "certification" in text or "SOP" in text


def test_families_are_listed_in_the_thesis_order() -> None:
    """The index's family pages and the generated kinds.md run chapter 2, 3, 4, 5, SOP, 6."""
    import importlib.util

    block = re.search(r":caption: Problem families\n(.*?)```", _toctree_entries(), re.DOTALL)
    entries = [e for e in re.findall(r"^(families/[\w-]+)$", block.group(1), re.MULTILINE)]
    pages = sorted(p.stem for p in (DOCS / "families").glob("*.md"))
    assert sorted(e.split("/")[1] for e in entries) == pages  # every page listed by name
    titles = [
        next(
            line
            for line in (DOCS / f"{e}.md").read_text(encoding="utf-8").splitlines()
            if line.startswith("# ")
        )
        for e in entries
    ]
    chapters = [_chapter(t)[0] for t in titles]
    assert chapters == sorted(chapters), titles
    spec = importlib.util.spec_from_file_location("generated", DOCS / "generated.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    table = module.generated_pages()["kinds.md"].split("## Methods by problem type")[0]
    kinds = re.findall(r"^\| `(\w+)` \| ([^|]+) \|", table, re.M)  # the kinds table
    order = [_chapter(title) for _, title in kinds]
    assert order == sorted(order), kinds
    assert {k for k, _ in kinds[-2:]} == {"budgeted_problem", "fleet_problem"}  # ch. 6, last


def test_notebook_titles_share_one_style() -> None:
    """Every notebook opens with "# Chapter N — ..." (one style, the chapter it teaches)."""
    import json

    for path in sorted((ROOT / "notebooks").glob("*.ipynb")):
        cells = json.loads(path.read_text(encoding="utf-8"))["cells"]
        first = "".join(next(c for c in cells if c["cell_type"] == "markdown")["source"])
        title = first.splitlines()[0]
        assert re.fullmatch(r"# Chapter \d(, §\d\.\d)? — [a-z].+", title), f"{path.name}: {title}"


# ------------------------------------------------------------------ the built site, in Chromium
def _browser():
    """Headless Chromium driven by Debian's chromedriver (never a downloaded driver)."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    binary = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver")
    if binary is None or driver is None:
        pytest.fail(
            "Chromium and chromedriver are needed: apt-get install chromium chromium-driver"
        )
    options = webdriver.ChromeOptions()
    options.binary_location = binary
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"):
        options.add_argument(flag)
    options.add_argument("--window-size=1280,900")
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service(executable_path=driver), options=options)


@pytest.fixture(scope="module")
def site_url() -> Iterator[str]:
    """The built site served over HTTP on a free local port (so a missing file is a 404)."""
    if not (SITE / "index.html").is_file():
        pytest.fail(f"no built site in {SITE}: run `python docs/build.py` first")
    handler = functools.partial(_QuietHandler, directory=str(SITE))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()


class _QuietHandler(http.server.SimpleHTTPRequestHandler):
    missing: list[str] = []

    def log_message(self, format: str, *args) -> None:  # noqa: A002 - the base class's name
        pass

    def send_error(self, code: int, message: str | None = None, explain: str | None = None):
        _QuietHandler.missing.append(f"{code} {self.path}")
        super().send_error(code, message, explain)


@pytest.fixture(scope="module")
def browser():
    """One headless Chromium for the module's tests."""
    driver = _browser()
    try:
        yield driver
    finally:
        driver.quit()


def _open(browser, url: str) -> dict:
    """Load a page; return its title, heading, failed loads and console errors."""
    _QuietHandler.missing.clear()
    browser.get_log("browser")  # drop what earlier pages logged
    browser.get(url)
    browser.execute_script("return document.fonts ? document.fonts.ready : null")
    state = browser.execute_script(
        """
        const broken = Array.from(document.images)
            .filter(i => !(i.complete && i.naturalWidth > 0)).map(i => i.src);
        const sheets = Array.from(document.styleSheets).map(s => s.href).filter(h => h);
        const h1 = document.querySelector('h1');
        return {title: document.title, h1: h1 ? h1.textContent : null,
                broken: broken, sheets: sheets,
                math: document.querySelectorAll('mjx-container').length};
        """
    )
    errors = [e["message"] for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    state["console"] = errors
    state["missing"] = list(_QuietHandler.missing)
    return state


@pytest.mark.docs
def test_index_renders(browser, site_url: str) -> None:
    """The built index opens in Chromium with its title, styles and no failed resource load."""
    page = _open(browser, site_url + "index.html")
    assert "taopt" in page["title"], page["title"]
    assert page["h1"] and "taopt" in page["h1"]
    assert any("furo" in href for href in page["sheets"]), page["sheets"]
    assert not page["missing"], f"missing resources: {page['missing']}"
    assert not page["broken"], f"images that did not load: {page['broken']}"
    assert not page["console"], f"browser errors: {page['console']}"
    shot = Path(os.environ.get("TAOPT_DOCS_SCREENSHOT", SITE.parent / "screenshot.png"))
    shot.parent.mkdir(parents=True, exist_ok=True)
    assert browser.save_screenshot(str(shot))


@pytest.mark.docs
def test_api_page_renders(browser, site_url: str) -> None:
    """An API page generated from the docstrings opens with its module title and no failed load."""
    page = _open(browser, site_url + API_PAGE)
    assert "taopt.models.routing" in page["title"], page["title"]
    assert "solve_routing" in browser.page_source
    assert not page["missing"], f"missing resources: {page['missing']}"
    assert not page["broken"], f"images that did not load: {page['broken']}"
    assert not page["console"], f"browser errors: {page['console']}"


@pytest.mark.docs
def test_notebook_page_shows_outputs(browser, site_url: str) -> None:
    """A notebook page shows the outputs computed at build time: tables and loaded figures."""
    page = _open(browser, site_url + "notebooks/02_drift_routing.html")
    assert not page["missing"], f"missing resources: {page['missing']}"
    assert not page["broken"], f"images that did not load: {page['broken']}"
    assert not page["console"], f"browser errors: {page['console']}"
    figures = browser.execute_script(
        "return Array.from(document.querySelectorAll('.cell_output img'))"
        ".filter(i => i.naturalWidth > 100).length"
    )
    assert figures >= 1, f"{figures} figures rendered"
    assert "optimal" in browser.find_element("tag name", "article").text


@pytest.mark.docs
def test_formulation_page_typesets_equations(browser, site_url: str) -> None:
    """The chapter 2 page's LaTeX is typeset by MathJax, with the thesis's equation tags."""
    page = _open(browser, site_url + "families/routing.html")
    assert not page["missing"], f"missing resources: {page['missing']}"
    assert not page["console"], f"browser errors: {page['console']}"
    from selenium.webdriver.support.ui import WebDriverWait

    WebDriverWait(browser, 60).until(
        lambda d: d.execute_script("return document.querySelectorAll('mjx-container').length") >= 4
    )
    text = browser.find_element("tag name", "article").text
    for tag in ("(2.2)", "(2.3)", "(2.4)", "(2.5)"):
        assert tag in text, f"equation {tag} not shown"
